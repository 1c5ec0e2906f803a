//! What a sweep can run: the [`SweepMethod`] trait and the parameter values an experiment
//! lists (the table of methods by name is `registry.rs`).
//!
//! A method declares its parameters ([`SweepParam`]: name, default, smallest value, whether
//! `"all"` is allowed, doc); the experiment file is validated against them, so a new method is
//! sweepable by adding one implementation and one line in [`find_method`].

use crate::approx::GpuContext;
use crate::error::Result;
use crate::image_io::RgbImage;
use crate::scene::Scene;

/// One value of a swept parameter: a count, or `"all"` (e.g. the thesis's N = all, every
/// particle on the ray with the lit model).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum ParamValue {
    Count(u32),
    /// Ordered after every count, so that sorted values put it last (as on the plots).
    All,
}

impl ParamValue {
    /// The value a renderer takes: `All` is `u32::MAX` ([`crate::approx::N_EXACT_ALL`]).
    pub fn as_u32(self) -> u32 {
        match self {
            ParamValue::Count(n) => n,
            ParamValue::All => crate::approx::N_EXACT_ALL,
        }
    }
}

impl std::fmt::Display for ParamValue {
    /// `7` or `all`: the form of labels, tables and file names.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ParamValue::Count(n) => write!(f, "{n}"),
            ParamValue::All => f.write_str("all"),
        }
    }
}

impl serde::Serialize for ParamValue {
    /// A JSON number, or the string `"all"`.
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        match self {
            ParamValue::Count(n) => s.serialize_u32(*n),
            ParamValue::All => s.serialize_str("all"),
        }
    }
}

/// Where a parameter's value comes from when an experiment entry does not list it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ParamDefault {
    Value(ParamValue),
    /// The experiment's `[reference] spp` (so a Riemann run differs from the reference only in
    /// its integrator).
    ReferenceSpp,
}

/// A parameter a method declares (the sweep's view of the approximation registry's
/// `ParamSpec`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SweepParam {
    pub name: &'static str,
    pub default: ParamDefault,
    /// The smallest count accepted.
    pub min: u32,
    /// The largest count accepted.
    pub max: u32,
    /// Whether `"all"` is a value.
    pub accepts_all: bool,
    /// Whether a run's label and file names leave the parameter out at its default value, so
    /// that runs keep the names they had before the method gained it.
    pub quiet_default: bool,
    pub doc: &'static str,
}

/// What one run produced.
#[derive(Debug, Clone)]
pub struct RunImage {
    /// Linear RGB, row 0 at the top.
    pub image: RgbImage,
    /// The GPU time in seconds for GPU methods (the wall time would include shader
    /// compilation); `None` for CPU methods, whose wall time the sweep measures.
    pub gpu_seconds: Option<f64>,
    /// Things the user should know about this image (dropped hits, lavapipe's loop limit).
    pub warnings: Vec<String>,
}

/// What the runs of one sweep share: the thread count and the GPU context, opened on the first
/// GPU run and kept for the rest of the sweep.
#[derive(Default)]
pub struct SweepContext {
    /// Worker threads of CPU renders; `None` uses rayon's default.
    pub threads: Option<usize>,
    gpu: Option<GpuContext>,
}

impl SweepContext {
    pub fn new(threads: Option<usize>) -> SweepContext {
        SweepContext { threads, gpu: None }
    }

    /// The adapter's name, once a GPU run opened the context.
    pub fn adapter_name(&self) -> Option<String> {
        self.gpu.as_ref().map(|g| {
            format!(
                "{} ({}, {})",
                g.adapter.name, g.adapter.backend, g.adapter.device_type
            )
        })
    }

    /// The GPU context, opened on first use (on the first adapter wgpu finds).
    pub fn gpu(&mut self) -> Result<&GpuContext> {
        let gpu = match self.gpu.take() {
            Some(gpu) => gpu,
            None => GpuContext::new(None)?,
        };
        Ok(self.gpu.insert(gpu))
    }
}

/// A method a sweep can run: the CPU reference with another integrator, or a GPU approximation.
pub trait SweepMethod: Sync {
    /// The name experiment files use (`method = "NAME"`).
    fn name(&self) -> &'static str;
    /// The parameters an experiment may list, in the order runs and labels use.
    fn params(&self) -> &[SweepParam];
    /// Refuses scenes the method cannot render, before any work is done.
    fn check_scene(&self, scene: &Scene) -> Result<()>;
    /// Renders `scene` with one value per declared parameter (`values` in [`Self::params`]
    /// order; `"all"` as `u32::MAX`).
    fn render(
        &self,
        ctx: &mut SweepContext,
        scene: &Scene,
        values: &[(&'static str, u32)],
    ) -> Result<RunImage>;
}

impl std::fmt::Debug for dyn SweepMethod {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The value of `name` in `values`, or `default`.
pub fn value_of(values: &[(&'static str, u32)], name: &str, default: u32) -> u32 {
    values
        .iter()
        .find(|(k, _)| *k == name)
        .map_or(default, |(_, v)| *v)
}
