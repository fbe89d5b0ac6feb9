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
pub mod e57;
mod e57_fast;
pub mod ply;
pub mod scale;
pub mod stream;

pub use ascii::{ascii_layout, data_columns, detect_style, parse_ascii, parse_body, read_ascii_file, write_ascii, AsciiOptions, DataStart, Layout, Parsed, Style};
pub use e57::{read_e57, E57Points};
pub use ply::{read_ply, read_ply_file, PlyFile, PlyPoints, VertexRecords};
pub use stream::{AsciiStream, PlyStream};
pub use scale::scale_in_place;
