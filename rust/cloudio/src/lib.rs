//! Parallel reading and writing of ASCII point clouds.
//!
//! The reader takes the bytes of an XYZ / CSV / TXT file: values separated by
//! commas, semicolons, spaces or tabs; optional header lines before the data;
//! blank lines and lines starting with `#` or `//` skipped anywhere; extra
//! columns ignored. With a header naming `x`, `y`, `z` columns those are used,
//! otherwise the first columns. Errors name the 1-based line of the file.

//!
//! Also binary formats: PLY ([`read_ply`], ASCII and binary, counts checked against the
//! file size) and E57 ([`read_e57`], through the pure-Rust `e57` crate).

pub mod ascii;
pub mod cut;
pub mod e57;
mod e57_fast;
pub mod e57_stream;
pub mod ply;
pub mod sample;
pub mod scale;
pub mod stream;

/// The error of a failed read of file `what`: a file that ends too early is a format
/// error (truncated), any other I/O failure an access error.
pub(crate) fn read_error(what: &str, e: std::io::Error) -> gagekit_core::GkError {
    let m = format!("{what}: cannot be read ({e})");
    if e.kind() == std::io::ErrorKind::UnexpectedEof {
        gagekit_core::GkError::file_format(m)
    } else {
        gagekit_core::GkError::file_access(m)
    }
}

pub use ascii::{ascii_layout, data_columns, detect_style, parse_ascii, parse_body, read_ascii_file, write_ascii, AsciiFile, AsciiOptions, DataStart, Layout, Parsed, Style};
pub use cut::{cut_chunk, merged_scatter, Keep, Moments, RegionCut, SampleSpec, Sampled, Scatter, MOMENTS_LEN};
pub use e57::{read_e57, E57Points};
pub use e57_stream::E57Stream;
pub use ply::{read_ply, read_ply_file, PlyAsciiStream, PlyFile, PlyPoints, VertexRecords};
pub use stream::{direct_buffer_len, AsciiStream, PlyStream, DIRECT_ALIGN};
pub use sample::{keys_below, sample_key};
pub use scale::scale_in_place;

#[cfg(test)]
mod error_kind_tests {
    use gagekit_core::ErrorKind;

    #[test]
    fn a_short_file_is_a_format_error_and_a_failed_open_an_access_error() {
        let eof = super::read_error("f", std::io::Error::from(std::io::ErrorKind::UnexpectedEof));
        assert_eq!(eof.kind, ErrorKind::FileFormat);
        let denied = super::read_error("f", std::io::Error::from(std::io::ErrorKind::PermissionDenied));
        assert_eq!(denied.kind, ErrorKind::FileAccess);
        let missing = crate::ascii::read_ascii_file(std::path::Path::new("/nonexistent/gagekit/none.xyz"), &Default::default(), "none.xyz");
        assert_eq!(missing.map(|_| ()).unwrap_err().kind, ErrorKind::FileAccess);
    }
}
