//! Parallel reading and writing of ASCII point clouds.
//!
//! The reader takes the bytes of an XYZ / CSV / TXT file: values separated by
//! commas, semicolons, spaces or tabs; optional header lines before the data;
//! blank lines and lines starting with `#` or `//` skipped anywhere; extra
//! columns ignored. With a header naming `x`, `y`, `z` columns those are used,
//! otherwise the first columns. Errors name the 1-based line of the file.

pub mod ascii;

pub use ascii::{parse_ascii, write_ascii, AsciiOptions, Parsed};
