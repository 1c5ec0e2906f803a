//! `pgt.sweep`, `pgt.merge` and `pgt.bench`: the commands of the same names through the
//! library entry points they run (`report::sweep_page::sweep_into_report`,
//! `parts::merge_files`, `bench::run`), so reports, merged images and tables are the CLI's.

use crate::arrays::image_to_array;
use crate::errors::{input_error, warn, IntoPy};
use pgt::report::sweep_page::{sweep_into_report, SweepWatch};
use pgt::sweep::{load_scene, Experiment, Progress};
use pyo3::prelude::*;
use std::path::PathBuf;

/// A sweep watched from Python: nothing is printed (the report holds every figure).
struct Quiet;

impl SweepWatch for Quiet {
    fn show(&mut self, _: Progress) {}
}

/// Runs an experiment file and writes its report (`pgt sweep EXPERIMENT --report DIR`);
/// returns (the number of runs, the report's page).
#[pyfunction]
#[pyo3(signature = (experiment, report, *, size=None, threads=None))]
pub fn sweep(
    py: Python<'_>,
    experiment: PathBuf,
    report: PathBuf,
    size: Option<(u32, u32)>,
    threads: Option<usize>,
) -> PyResult<(usize, PathBuf)> {
    if let Some((w, h)) = size {
        pgt::scene::check_image_size(w as i64, h as i64)
            .map_err(|e| input_error(py, format!("size: {e}")))?;
    }
    let mut experiment = Experiment::load(&experiment).py_err(py)?;
    if let Some((w, h)) = size {
        experiment.size = Some([w, h]);
    }
    let scene = py.detach(|| load_scene(&experiment)).py_err(py)?;
    for w in &scene.warnings {
        warn(py, w, 2)?;
    }
    py.detach(|| sweep_into_report(&report, &experiment, &scene, threads, false, &mut Quiet))
        .py_err(py)
}

/// Joins the parts of a cluster render (`pgt merge PART... -o OUT`): returns (image, err),
/// err None where the parts have no error layer, and writes `output` where given.
#[pyfunction]
#[pyo3(signature = (parts, output=None, *, exposure=0.0))]
pub fn merge<'py>(
    py: Python<'py>,
    parts: Vec<PathBuf>,
    output: Option<PathBuf>,
    exposure: f32,
) -> PyResult<(Bound<'py, PyAny>, Option<Bound<'py, PyAny>>)> {
    if !exposure.is_finite() {
        return Err(input_error(py, "exposure must be a finite number"));
    }
    let (image, error) = py
        .detach(|| -> pgt::Result<_> {
            let (image, error) = pgt::parts::merge_files(&parts)?;
            if let Some(path) = &output {
                let layers: Vec<(&str, &pgt::image_io::RgbImage)> =
                    error.iter().map(|e| ("err", e)).collect();
                pgt::image_io::write_image(path, &image, &layers, exposure)?;
            }
            Ok((image, error))
        })
        .py_err(py)?;
    let error = error.map(|e| image_to_array(py, e).into_any());
    Ok((image_to_array(py, image).into_any(), error))
}

/// Runs `pgt bench` and returns the tables it prints (the single renders', then the
/// sequences'), joined.
#[pyfunction(name = "bench")]
#[pyo3(signature = (
    *, size=512, workloads=vec!["1uun".to_string(), "random".to_string(), "million".to_string()],
    no_baselines=false, accuracy=false, threads=None, repeat=1, frames=None,
    data=PathBuf::from("../shared/data")
))]
#[allow(clippy::too_many_arguments)]
pub fn bench_tables(
    py: Python<'_>,
    size: u32,
    workloads: Vec<String>,
    no_baselines: bool,
    accuracy: bool,
    threads: Option<usize>,
    repeat: u32,
    frames: Option<usize>,
    data: PathBuf,
) -> PyResult<String> {
    pgt::scene::check_image_size(size as i64, size as i64)
        .map_err(|e| input_error(py, format!("size: {e}")))?;
    if repeat < 1 {
        return Err(input_error(py, "repeat must be at least 1"));
    }
    let workloads = workloads
        .iter()
        .map(|w| {
            pgt::bench::Workload::named(w).ok_or_else(|| {
                input_error(
                    py,
                    format!(
                        "workloads: unknown workload '{w}' (one of {})",
                        pgt::bench::Workload::names().join(", ")
                    ),
                )
            })
        })
        .collect::<PyResult<Vec<_>>>()?;
    let options = pgt::bench::BenchOptions {
        size,
        workloads,
        no_baselines,
        accuracy,
        threads,
        repeat,
        frames,
        data,
    };
    py.detach(|| {
        let mut text = String::new();
        pgt::bench::run(&options, &mut |table| {
            text.push_str(table);
            Ok(())
        })
        .map(|()| text)
    })
    .py_err(py)
}

/// Adds this module's functions to the extension module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(sweep, m)?)?;
    m.add_function(wrap_pyfunction!(merge, m)?)?;
    m.add_function(wrap_pyfunction!(bench_tables, m)?)?;
    Ok(())
}
