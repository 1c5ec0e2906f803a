//! The export formats of `pgt export` (docs/design.md §7): a table of `f64` columns as CSV or
//! as binary PLY, the files pgt's own readers take back ([`crate::formats::xyz_csv`],
//! [`crate::formats::ply`]).
//!
//! * **CSV**: a header of the column names, one row a line, every number in Rust's shortest
//!   round-trip notation (reading it back as f64 gives the same bits). ∞ is written `inf`, which
//!   C's `strtod`, Python's `float`, numpy and Rust's `f64::from_str` all read as +∞.
//! * **PLY**: `binary_little_endian 1.0`, one `vertex` element per row with a `double` property
//!   per column; ∞ is the IEEE 754 +∞ double.
//!
//! Which columns a particle has is the scene's business (`crate::scene::export`).

use crate::error::PgtError;
use std::io::Write;
use std::path::Path;

/// The export formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ExportFormat {
    Csv,
    Ply,
}

impl ExportFormat {
    /// From the output's extension.
    pub fn from_path(path: &Path) -> crate::Result<Self> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("csv") => Ok(ExportFormat::Csv),
            Some("ply") => Ok(ExportFormat::Ply),
            _ => Err(PgtError::Usage(format!(
                "{}: unknown export format; use a .csv or .ply extension",
                path.display()
            ))),
        }
    }
}

/// Writes the CSV form (see the module docs): the header `columns`, then `rows`.
pub fn write_csv(
    w: &mut impl Write,
    columns: &[&str],
    rows: impl Iterator<Item = Vec<f64>>,
) -> std::io::Result<()> {
    writeln!(w, "{}", columns.join(","))?;
    for r in rows {
        let cells: Vec<String> = r.iter().map(|v| format!("{v:?}")).collect();
        writeln!(w, "{}", cells.join(","))?;
    }
    Ok(())
}

/// Writes the binary PLY form (see the module docs): one vertex per row of `rows`, a `double`
/// property per name of `columns`.
pub fn write_ply(
    w: &mut impl Write,
    columns: &[&str],
    rows: impl ExactSizeIterator<Item = Vec<f64>>,
) -> std::io::Result<()> {
    writeln!(w, "ply")?;
    writeln!(w, "format binary_little_endian 1.0")?;
    writeln!(
        w,
        "comment pgt export: linear RGB colour, opacity = Theta_max, sigma = extinction in 1/m (inf for opacity 1)"
    )?;
    writeln!(w, "element vertex {}", rows.len())?;
    for c in columns {
        writeln!(w, "property double {c}")?;
    }
    writeln!(w, "end_header")?;
    for r in rows {
        for v in r {
            w.write_all(&v.to_le_bytes())?;
        }
    }
    Ok(())
}
