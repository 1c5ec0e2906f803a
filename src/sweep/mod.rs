//! Sweeps (docs/design.md §5, §7 `pgt sweep`): the reference once, an approximation for each
//! parameter combination an experiment lists, each compared with the reference (and with a
//! baseline run where one is named). The results feed `report::sweep_page`: a table (the
//! thesis's Tables 6.1/6.2: SSIM per channel and mean, in %) and SVG plots of error and time
//! against the swept parameter (the thesis's Figures 6.2/6.3).
//!
//! The experiment file (TOML; unknown keys, methods and parameters are errors that name the
//! file:line and list the valid ones):
//!
//! ```toml
//! scene = "scene.toml"        # relative to the experiment file
//! size = [256, 256]           # optional: overrides the scene's image size
//! data_range = 1.0            # optional: SSIM/PSNR data range (default as in `pgt compare`)
//! plot_x = "samples"          # optional: the plots' x axis (default: the most varied parameter)
//!
//! [reference]                 # optional: the one reference render
//! spp = 1
//! tol = 1e-5                  # overrides the scene's quadrature tolerance
//!
//! [[approximations]]
//! method = "riemann"          # the reference with the thesis's midpoint Riemann sums (CPU)
//! samples = [1, 2, 5, 10, 50, 100]
//! spp = [1]                   # optional, default: the reference's spp
//!
//! [[approximations]]
//! method = "thesis"           # a GPU approximation (docs/design.md §4)
//! samples = 100               # one value or a list
//! n_exact = [1, 2, 3, 5, "all"]
//! baseline = { n_exact = "all" }
//!
//! [[approximations]]
//! method = "thesis-cpu"       # the same scheme in f64 on the CPU (for the float32 stage)
//! n_exact = [5, "all"]
//!
//! [[attribution]]             # optional: split a run's error into causes (docs/design.md §5)
//! run = { method = "thesis", samples = 100, n_exact = 5 }
//! steps = [
//!     { cause = "float32",  swap = { method = "thesis-cpu" } },
//!     { cause = "n_exact",  swap = { n_exact = "all" } },
//!     { cause = "overlap",  swap = { method = "riemann" } },
//!     { cause = "sampling", swap = "reference" },
//! ]
//!
//! [[conventions]]             # optional: the baseline comparisons again, images stored otherwise
//! name = "max-8bit"
//! normalize = "max"           # "none" (default), "max" or "channel-max"
//! quantize = 8                # optional: bits per channel after normalisation
//! ```
//!
//! * `method` names any method of [`find_method`]: `riemann` and `thesis-cpu` (CPU), and every GPU method of the
//!   approximation registry (`pgt approx --list-methods`); every other key is one of the method's parameters, with one value or a
//!   list of values (whole numbers, or `"all"` where the parameter allows it: `n_exact`).
//!   A parameter an entry does not list takes its default (the table in `riemann.rs`, and each
//!   GPU method's parameter table in `src/approx/methods/`). Each entry runs the Cartesian product of its lists, parameters in the method's
//!   declared order (the first varying slowest); a run's label is `method p1=v1 p2=v2 …` and
//!   its image `method_p1_v1_p2_v2….png`.
//! * `baseline = { [method = "NAME",] param = value, … }` compares each run of the entry also
//!   with another run of the experiment (in the reference's place), as the thesis's "GT"
//!   column does (its own scheme with N = all). The baseline run of a run is: the baseline's
//!   method (default: the entry's), each parameter as the baseline table gives it, else the
//!   run's own value of that parameter, else the method's default. It must be one of the
//!   experiment's runs (an error at the `baseline` line otherwise). With the example above,
//!   `thesis samples=100 n_exact=2` is compared with `thesis samples=100 n_exact=all`. The
//!   comparison with the exact reference is always made too.
//! * `[[attribution]]` explains the error of `run` (one of the experiment's runs, named by its
//!   method and parameters; unlisted parameters take their defaults) by a chain of stage swaps:
//!   each step's `swap` is applied to the previous step's run the way a `baseline` table is
//!   (method and parameters replaced, the rest kept), and must name a run of the experiment;
//!   `swap = "reference"` ends the chain at the exact reference (a chain that stops earlier
//!   gets a `residual` cause for the rest). Any method works whose stages have exact
//!   counterparts among the sweep's methods and parameters. For `thesis`: `float32` (the same
//!   scheme in f64, `thesis-cpu`), `n_exact` (N = all), `overlap` (exact intervals instead of
//!   whole particles in entry order: `riemann`, the reference with the same Riemann sums) and
//!   `sampling` (the adaptive quadrature: the reference). What a cause's share means, and how
//!   the interaction is reported, is in [`attribution`].
//! * `[[conventions]]` repeat every comparison of a run with its baseline run after both images
//!   are normalised by their maximum and rounded to a bit depth, each image on its own (what
//!   each choice means: [`conventions`]); `sweep.json` files them under the run's
//!   `baseline.conventions.NAME`. They need a run with a baseline.
//!
//! The GPU methods run on the first adapter wgpu finds, one context for the whole sweep; their
//! time is the GPU time, the CPU methods' the wall time.

pub mod attribution;
pub mod conventions;
pub mod experiment;
pub mod gpu;
pub mod method;
pub mod registry;
pub mod riemann;
pub mod run_result;
pub mod runner;
pub mod thesis_cpu;

pub use attribution::{AttributionResult, CauseResult};
pub use experiment::{Attribution, AttributionStep, Experiment, ReferenceSpec, Run};
pub use method::{ParamDefault, ParamValue, RunImage, SweepContext, SweepMethod, SweepParam};
pub use registry::{find_method, method_names};
pub use run_result::{BaselineResult, RunResult};
pub use runner::{
    load_scene, reference_key, run_sweep, Progress, ReferenceInfo, SweepOptions, SweepResults,
    Unconverged,
};
