//! `pgt merge PART... -o OUT`: the whole image from the parts of a cluster render (docs/design.md §7,
//! docs/cluster.md), bit-identical to a one-machine `pgt render`, err layer included. The checks and
//! the part format are in [`pgt::parts`]: a file that is not a part, a missing or duplicated
//! part, or parts of different renders exit 2 with a message naming the file, and nothing is
//! written.

use super::output::{check_outputs, Output, OutputKind};
use super::Outcome;
use clap::Args;
use pgt::image_io::{write_image, RgbImage};
use pgt::parts::{error_figures, merge_files};
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct MergeArgs {
    /// The part files written by `pgt render SCENE --part I/N -o PART.exr`, in any order.
    #[arg(required = true)]
    pub parts: Vec<PathBuf>,
    /// Output image; the format follows the extension (.exr or .png).
    #[arg(short, long)]
    pub output: PathBuf,
    /// PNG exposure in stops (2^exposure scales the linear image before encoding).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub exposure: f32,
}

pub fn run(args: MergeArgs) -> anyhow::Result<Outcome> {
    check_outputs(&[Output::new("--output", &args.output, OutputKind::Image)])?;
    if !args.exposure.is_finite() {
        anyhow::bail!("--exposure must be a finite number");
    }
    let (image, error) = merge_files(&args.parts)?;
    let layers: Vec<(&str, &RgbImage)> = error.iter().map(|e| ("err", e)).collect();
    write_image(&args.output, &image, &layers, args.exposure)?;
    let mut line = format!(
        "merged {} parts into {} ({}x{})",
        args.parts.len(),
        args.output.display(),
        image.width,
        image.height
    );
    if let Some(e) = &error {
        // The same figures `pgt render` prints for the whole image.
        let (max, mean) = error_figures(e);
        line += &format!(", error estimate max {max:.3e} mean {mean:.3e}");
    }
    eprintln!("{line}");
    Ok(Outcome::Success)
}
