//! The byte layer every reader stands on (as chemfiles keeps its file layer apart from its
//! formats): what a reader needs of a file's bytes, written once and checked once.
//!
//! * [`source`]: a file read in checked pieces ([`ByteSource`]), for readers that keep it open;
//! * [`binary`]: numbers in either byte order ([`Endian`]) and a cursor ([`Reader`]) whose every
//!   read is checked against the bytes present, so that no count a header announces is
//!   allocated or trusted before the bytes are there;
//! * [`fortran`]: Fortran unformatted records, their two length markers checked ([`Fortran`]);
//! * [`text`]: numbered lines (every text format numbers them alike), fixed columns and numeric
//!   fields.
//!
//! Every refusal names the file and the byte offset (binary) or the line (text).

pub mod binary;
pub mod fortran;
pub mod source;
pub mod text;

pub use binary::{Endian, Reader};
pub use fortran::Fortran;
pub use source::{ByteSource, ReadSeek};
pub use text::{columns, lines, scan_lines, text_lines};
