//! The extension module `pgt._pgt` of the Python package `pgt` (docs/design.md §11): the pgt
//! library with numpy arrays in and out. Every function reaches the library entry point the
//! CLI reaches (`Scene::load`, `reference::render_controlled`, `approx::render_approx`,
//! `report::Compared`, `report::sequence_compare`, `parts`, `bench`, `image_io`), so values are the CLI's bit for bit; this crate only turns
//! Python arguments into the library's types and results into arrays. The Python half of the
//! package (`pgt/__init__.py`) holds the documented public functions.
//!
//! * [`arrays`]: numpy in and out, and where values are copied.
//! * [`errors`]: the `pgt.Error` hierarchy.
//! * [`settings`]: keyword arguments as scene-file and gate-file tables.
//! * [`scene`], [`frames`], [`render`], [`approx`], [`compare`], [`sequences`], [`tools`]
//!   (sweep, merge, bench), [`images`]: one per part of the API.

mod approx;
mod arrays;
mod cameras;
mod compare;
mod errors;
mod frames;
mod gaussians;
mod images;
mod render;
mod scene;
mod sequences;
mod settings;
mod tools;

use pyo3::prelude::*;

#[pymodule]
fn _pgt(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // As the CLI's main does: keeps Mesa's device-select layer from printing an XDG_RUNTIME_DIR
    // error on every GPU call where no Wayland session exists. Importing the module is the
    // earliest point the package runs, before it starts any thread of its own.
    pgt::approx::context::quiet_device_select_probe();
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add(
        "DEFAULT_PIXELS_PER_DEGREE",
        pgt::metrics::flip::DEFAULT_PIXELS_PER_DEGREE,
    )?;
    m.add("N_EXACT_ALL", pgt::approx::N_EXACT_ALL)?;
    m.add_class::<scene::Scene>()?;
    m.add_function(wrap_pyfunction!(scene::load_scene, m)?)?;
    m.add_function(wrap_pyfunction!(gaussians::gaussian_particles, m)?)?;
    m.add_function(wrap_pyfunction!(cameras::dataset_cameras, m)?)?;
    m.add_class::<frames::Frames>()?;
    m.add_function(wrap_pyfunction!(frames::load_frames, m)?)?;
    m.add_class::<render::RenderResult>()?;
    m.add_function(wrap_pyfunction!(render::render, m)?)?;
    m.add_class::<approx::ApproxResult>()?;
    m.add_function(wrap_pyfunction!(approx::approx, m)?)?;
    m.add_function(wrap_pyfunction!(approx::approx_methods, m)?)?;
    compare::register(m)?;
    sequences::register(m)?;
    tools::register(m)?;
    m.add_function(wrap_pyfunction!(images::read_image, m)?)?;
    m.add_function(wrap_pyfunction!(images::write_image, m)?)?;
    Ok(())
}
