//! The experiment file (format: the module documentation of [`crate::sweep`]): parsing with
//! file:line errors, validation of every entry against its method's declared parameters, and the
//! expansion of each `[[approximations]]` entry into runs (the Cartesian product of its lists),
//! each with the index of its baseline run where the entry names one.

use super::conventions::{Convention, MAX_QUANTIZE_BITS};
use super::method::{ParamDefault, ParamValue, SweepMethod, SweepParam};
use super::registry::{find_method, method_names};
use crate::error::{toml_error, PgtError, Result, SourceText};
use crate::reference::MAX_SPP;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use toml::Spanned;

/// The file as TOML sees it.
#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct ExperimentFile {
    scene: PathBuf,
    size: Option<Spanned<[u32; 2]>>,
    data_range: Option<Spanned<f64>>,
    reference: Option<Spanned<ReferenceSpec>>,
    approximations: Vec<BTreeMap<Spanned<String>, Spanned<toml::Value>>>,
    plot_x: Option<Spanned<String>>,
    #[serde(default)]
    attribution: Vec<AttributionFile>,
    #[serde(default)]
    conventions: Vec<Spanned<Convention>>,
}

/// An `[[attribution]]` table as TOML sees it.
#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct AttributionFile {
    run: Spanned<toml::Value>,
    steps: Vec<StepFile>,
}

/// One `{ cause = "…", swap = { … } | "reference" }` of an attribution's `steps`.
#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct StepFile {
    cause: String,
    swap: Spanned<toml::Value>,
}

/// Options of the one reference render.
#[derive(Debug, Clone, Default, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReferenceSpec {
    /// Stratified k×k samples per pixel (default 1).
    pub spp: Option<u32>,
    /// Overrides the scene's quadrature tolerance.
    pub tol: Option<f64>,
}

/// A validated experiment.
#[derive(Debug, Clone, PartialEq)]
pub struct Experiment {
    /// The experiment file.
    pub path: PathBuf,
    /// The scene, resolved against the experiment file's folder.
    pub scene: PathBuf,
    pub size: Option<[u32; 2]>,
    pub data_range: Option<f64>,
    pub reference: ReferenceSpec,
    /// Every run of every entry, in file order.
    pub runs: Vec<Run>,
    /// The parameter on the plots' x axis (`plot_x`); `None`: the one with the most values.
    pub plot_x: Option<&'static str>,
    /// The error attributions (`[[attribution]]`), in file order.
    pub attributions: Vec<Attribution>,
    /// The baseline comparisons' other conventions (`[[conventions]]`), in file order.
    pub conventions: Vec<Convention>,
}

/// An error attribution (`[[attribution]]`): a run, and a chain of runs each with one more
/// stage swapped for its exact counterpart, ending at the reference (or not: what is left is
/// then the `residual` cause).
#[derive(Debug, Clone, PartialEq)]
pub struct Attribution {
    /// The index in [`Experiment::runs`] of the run explained.
    pub run: usize,
    pub steps: Vec<AttributionStep>,
}

/// One stage swap of an attribution: the cause it removes and the run without it.
#[derive(Debug, Clone, PartialEq)]
pub struct AttributionStep {
    /// The cause's name (`overlap`, `sampling`, `n_exact`, `float32`, …).
    pub cause: String,
    /// The index of the run with this stage (and the ones before) exact; `None`: the exact
    /// reference.
    pub run: Option<usize>,
}

/// One parameter combination of one method.
#[derive(Debug, Clone, PartialEq)]
pub struct Run {
    /// The method's name ([`find_method`] finds it).
    pub method: &'static str,
    /// One value per declared parameter of the method, in its declared order (the plots' x axis
    /// is chosen among them).
    pub params: Vec<(&'static str, ParamValue)>,
    /// The index in [`Experiment::runs`] of the run this one is also compared with (`baseline`).
    pub baseline: Option<usize>,
}

impl Run {
    /// `thesis samples=100 n_exact=all`: every parameter but those a method leaves out of
    /// labels at their default ([`SweepParam::quiet_default`]).
    pub fn label(&self) -> String {
        let declared = find_method(self.method).map_or(&[][..], |m| m.params());
        let mut s = self.method.to_string();
        for (k, v) in &self.params {
            let quiet = declared
                .iter()
                .any(|p| p.name == *k && p.quiet_default && p.default == ParamDefault::Value(*v));
            if !quiet {
                let _ = write!(s, " {k}={v}");
            }
        }
        s
    }

    /// `thesis_samples_100_n_exact_all`: the stem of the run's files.
    pub fn file_stem(&self) -> String {
        self.label().replace([' ', '='], "_")
    }

    /// The value of parameter `name`.
    pub fn param(&self, name: &str) -> Option<ParamValue> {
        self.params
            .iter()
            .find(|(k, _)| *k == name)
            .map(|(_, v)| *v)
    }

    /// The values as renderers take them (`"all"` as `u32::MAX`).
    pub fn values(&self) -> Vec<(&'static str, u32)> {
        self.params.iter().map(|(k, v)| (*k, v.as_u32())).collect()
    }
}

/// A `baseline = { … }` table: the method (default: the entry's own) and the values that
/// replace the run's own.
#[derive(Debug)]
struct BaselineSpec {
    method: &'static dyn SweepMethod,
    values: Vec<(&'static str, ParamValue)>,
    line: usize,
}

/// One `[[approximations]]` entry, validated.
struct Entry {
    method: &'static dyn SweepMethod,
    lists: Vec<Vec<ParamValue>>,
    baseline: Option<BaselineSpec>,
}

impl Experiment {
    /// Reads and validates an experiment file.
    pub fn load(path: &Path) -> Result<Experiment> {
        let text = std::fs::read_to_string(path).map_err(|e| PgtError::io(path, e))?;
        Experiment::parse(&text, path)
    }

    /// Parses and validates the text of the experiment file `path`.
    pub fn parse(text: &str, path: &Path) -> Result<Experiment> {
        let file: ExperimentFile = toml::from_str(text).map_err(|e| toml_error(path, text, &e))?;
        let at = Validator {
            src: SourceText { path, text },
        };
        at.check_globals(&file)?;
        let reference = file
            .reference
            .as_ref()
            .map(|r| r.get_ref().clone())
            .unwrap_or_default();
        let ref_spp = reference.spp.unwrap_or(1);
        let mut entries = Vec::new();
        for table in &file.approximations {
            entries.push(at.entry(table, ref_spp)?);
        }
        let mut runs = Vec::new();
        for (entry, table) in entries.iter().zip(&file.approximations) {
            // Counted before they are made: a few long lists multiply to millions of runs.
            let count = entry
                .lists
                .iter()
                .try_fold(1usize, |n, l| n.checked_mul(l.len()))
                .filter(|&n| runs.len() + n <= MAX_RUNS);
            if count.is_none() {
                let line = table.keys().map(|k| at.src.line(k)).min().unwrap_or(1);
                return Err(at.src.error(
                    line,
                    format!(
                        "this entry's lists make more than {MAX_RUNS} runs in all (their product); sweep fewer values"
                    ),
                ));
            }
            runs.extend(entry.runs());
        }
        if runs.is_empty() {
            return Err(PgtError::in_file(
                path,
                "no approximation runs (every [[approximations]] list is empty)",
            ));
        }
        resolve_baselines(&at, &entries, ref_spp, &mut runs)?;
        let attributions = file
            .attribution
            .iter()
            .map(|a| at.attribution(a, &runs, ref_spp))
            .collect::<Result<Vec<_>>>()?;
        let plot_x = file
            .plot_x
            .as_ref()
            .map(|x| at.plot_x(x, &runs))
            .transpose()?;
        let conventions = at.conventions(&file.conventions, &runs)?;
        let base = path.parent().unwrap_or(Path::new("."));
        Ok(Experiment {
            path: path.to_path_buf(),
            scene: base.join(&file.scene),
            size: file.size.map(Spanned::into_inner),
            data_range: file.data_range.map(Spanned::into_inner),
            reference,
            runs,
            plot_x,
            attributions,
            conventions,
        })
    }
}

impl Entry {
    /// The Cartesian product of the lists, the first parameter varying slowest.
    fn runs(&self) -> Vec<Run> {
        let names: Vec<&'static str> = self.method.params().iter().map(|p| p.name).collect();
        let mut combos: Vec<Vec<(&'static str, ParamValue)>> = vec![Vec::new()];
        for (name, values) in names.iter().zip(&self.lists) {
            combos = combos
                .into_iter()
                .flat_map(|prefix| {
                    values.iter().map(move |&v| {
                        let mut p = prefix.clone();
                        p.push((*name, v));
                        p
                    })
                })
                .collect();
        }
        combos
            .into_iter()
            .map(|params| Run {
                method: self.method.name(),
                params,
                baseline: None,
            })
            .collect()
    }
}

/// The run that `run`'s baseline names: the baseline's method, each parameter from the
/// baseline table, else from `run` (same name), else the method's default.
fn baseline_run(run: &Run, spec: &BaselineSpec, ref_spp: u32) -> Run {
    let params = spec
        .method
        .params()
        .iter()
        .map(|p| {
            let given = spec.values.iter().find(|(k, _)| *k == p.name).map(|v| v.1);
            let v = given
                .or_else(|| run.param(p.name))
                .unwrap_or_else(|| default_value(p, ref_spp));
            (p.name, v)
        })
        .collect();
    Run {
        method: spec.method.name(),
        params,
        baseline: None,
    }
}

/// Sets each run's `baseline` index; an error at the `baseline` line when the named run is not
/// among the experiment's runs.
fn resolve_baselines(
    at: &Validator,
    entries: &[Entry],
    ref_spp: u32,
    runs: &mut [Run],
) -> Result<()> {
    let mut start = 0;
    for entry in entries {
        let n = entry.runs().len();
        if let Some(spec) = &entry.baseline {
            for i in start..start + n {
                let target = baseline_run(&runs[i], spec, ref_spp);
                let found = runs
                    .iter()
                    .position(|r| r.method == target.method && r.params == target.params);
                match found {
                    Some(j) => runs[i].baseline = Some(j),
                    None => {
                        return Err(at.src.error(
                            spec.line,
                            format!(
                                "the baseline of `{}` is `{}`, which is not one of the experiment's runs; list it in an [[approximations]] entry",
                                runs[i].label(),
                                target.label()
                            ),
                        ))
                    }
                }
            }
        }
        start += n;
    }
    Ok(())
}

/// A parameter's value when an entry does not list it.
fn default_value(p: &SweepParam, ref_spp: u32) -> ParamValue {
    match p.default {
        ParamDefault::Value(v) => v,
        ParamDefault::ReferenceSpp => ParamValue::Count(ref_spp),
    }
}

/// Most runs one experiment may have: each is a render, and a sweep of more is a typo or a
/// mistake in a list, not a plan.
pub const MAX_RUNS: usize = 10_000;

/// The checks of an experiment file's tables; errors name file:line through `src`.
struct Validator<'a> {
    src: SourceText<'a>,
}

impl Validator<'_> {
    /// Checks `size`, `data_range` and `[reference]` as `pgt render` and `pgt compare` would,
    /// but before anything is rendered and naming their line.
    fn check_globals(&self, file: &ExperimentFile) -> Result<()> {
        if let Some(size) = &file.size {
            let [w, h] = *size.get_ref();
            crate::scene::check_image_size(w as i64, h as i64)
                .map_err(|m| self.src.error(self.src.line(size), format!("size: {m}")))?;
        }
        if let Some(range) = &file.data_range {
            let r = *range.get_ref();
            if !(r.is_finite() && r > 0.0) {
                let message = format!("data_range must be a finite number > 0, got {r}");
                return Err(self.src.error(self.src.line(range), message));
            }
        }
        if let Some(reference) = &file.reference {
            let line = self.src.line(reference);
            let spec = reference.get_ref();
            if let Some(spp) = spec.spp.filter(|s| !(1..=MAX_SPP).contains(s)) {
                let message = format!("reference.spp must be between 1 and {MAX_SPP}, got {spp}");
                return Err(self.src.error(line, message));
            }
            if let Some(tol) = spec.tol.filter(|t| !(t.is_finite() && *t > 0.0)) {
                let message = format!("reference.tol must be a finite number > 0, got {tol}");
                return Err(self.src.error(line, message));
            }
        }
        Ok(())
    }

    /// Checks the `[[conventions]]`: names given once each, `quantize` in 1..=24 bits, and a
    /// run with a baseline for them to repeat.
    fn conventions(&self, tables: &[Spanned<Convention>], runs: &[Run]) -> Result<Vec<Convention>> {
        if let Some(first) = tables.first() {
            if runs.iter().all(|r| r.baseline.is_none()) {
                let message = "conventions repeat the comparisons with a baseline run, and no [[approximations]] entry has a `baseline`";
                return Err(self.src.error(self.src.line(first), message.into()));
            }
        }
        let mut out: Vec<Convention> = Vec::with_capacity(tables.len());
        for table in tables {
            let line = self.src.line(table);
            let c = table.get_ref();
            if c.name.trim().is_empty() {
                return Err(self
                    .src
                    .error(line, "conventions: name must not be empty".into()));
            }
            if out.iter().any(|o| o.name == c.name) {
                let message = format!("conventions: the name '{}' is given twice", c.name);
                return Err(self.src.error(line, message));
            }
            if let Some(bits) = c.quantize.filter(|b| !(1..=MAX_QUANTIZE_BITS).contains(b)) {
                let message = format!(
                    "conventions: quantize must be between 1 and {MAX_QUANTIZE_BITS} bits, got {bits}"
                );
                return Err(self.src.error(line, message));
            }
            out.push(c.clone());
        }
        Ok(out)
    }

    /// Validates one `[[approximations]]` table against its method's parameters.
    fn entry(
        &self,
        table: &BTreeMap<Spanned<String>, Spanned<toml::Value>>,
        ref_spp: u32,
    ) -> Result<Entry> {
        let get = |key: &str| table.iter().find(|(k, _)| k.get_ref() == key);
        let Some((_, method_value)) = get("method") else {
            let line = table.keys().map(|k| self.src.line(k)).min().unwrap_or(1);
            return Err(self.src.error(
                line,
                format!(
                    "an [[approximations]] entry needs `method = \"NAME\"` (one of {})",
                    method_names().join(", ")
                ),
            ));
        };
        let method = self.method(method_value)?;
        let mut lists: Vec<Option<Vec<ParamValue>>> = vec![None; method.params().len()];
        let mut baseline = None;
        for (key, value) in table {
            match key.get_ref().as_str() {
                "method" => {}
                "baseline" => baseline = Some(self.baseline(method, value)?),
                name => {
                    let (i, p) = self.param(method, key, name)?;
                    lists[i] = Some(self.values(p, value)?);
                }
            }
        }
        let lists = lists
            .into_iter()
            .zip(method.params())
            .map(|(l, p)| l.unwrap_or_else(|| vec![default_value(p, ref_spp)]))
            .collect();
        Ok(Entry {
            method,
            lists,
            baseline,
        })
    }

    /// The method a `method = "NAME"` value names.
    fn method(&self, value: &Spanned<toml::Value>) -> Result<&'static dyn SweepMethod> {
        let name = value.get_ref().as_str();
        name.and_then(find_method).ok_or_else(|| {
            self.src.error(
                self.src.line(value),
                format!(
                    "unknown method {}; the methods are {}",
                    value.get_ref(),
                    method_names().join(", ")
                ),
            )
        })
    }

    /// The declared parameter `name` of `method` and its index.
    fn param(
        &self,
        method: &'static dyn SweepMethod,
        key: &Spanned<String>,
        name: &str,
    ) -> Result<(usize, &'static SweepParam)> {
        let params = method.params();
        params
            .iter()
            .enumerate()
            .find(|(_, p)| p.name == name)
            .ok_or_else(|| {
                let valid: Vec<&str> = params.iter().map(|p| p.name).collect();
                let valid = if valid.is_empty() {
                    "it has none".to_string()
                } else {
                    format!("its parameters are {}", valid.join(", "))
                };
                self.src.error(
                    self.src.line(key),
                    format!(
                        "method {} has no parameter '{name}'; {valid} (and `baseline`)",
                        method.name()
                    ),
                )
            })
    }

    /// A parameter's values: one value or a list, each a count or `"all"`.
    fn values(&self, p: &SweepParam, value: &Spanned<toml::Value>) -> Result<Vec<ParamValue>> {
        let items: Vec<&toml::Value> = match value.get_ref() {
            toml::Value::Array(a) => a.iter().collect(),
            v => vec![v],
        };
        items
            .into_iter()
            .map(|v| {
                one_value(p, v).map_err(|m| {
                    self.src
                        .error(self.src.line(value), format!("{}: {m}", p.name))
                })
            })
            .collect()
    }

    /// A `baseline = { [method = "NAME",] param = value, … }` table.
    fn baseline(
        &self,
        entry_method: &'static dyn SweepMethod,
        value: &Spanned<toml::Value>,
    ) -> Result<BaselineSpec> {
        let line = self.src.line(value);
        let Some(table) = value.get_ref().as_table() else {
            return Err(self.src.error(
                line,
                "baseline must be a table, e.g. baseline = { n_exact = \"all\" }".into(),
            ));
        };
        let method = match table.get("method") {
            Some(m) => {
                let m = Spanned::new(value.span(), m.clone());
                self.method(&m)?
            }
            None => entry_method,
        };
        let mut values = Vec::new();
        for (name, v) in table.iter().filter(|(k, _)| k.as_str() != "method") {
            let key = Spanned::new(value.span(), name.clone());
            let (_, p) = self.param(method, &key, name)?;
            let v = one_value(p, v)
                .map_err(|m| self.src.error(line, format!("baseline {}: {m}", p.name)))?;
            values.push((p.name, v));
        }
        Ok(BaselineSpec {
            method,
            values,
            line,
        })
    }
}

impl Validator<'_> {
    /// `plot_x = "NAME"`: a parameter of at least one run.
    fn plot_x(&self, x: &Spanned<String>, runs: &[Run]) -> Result<&'static str> {
        runs.iter()
            .flat_map(|r| r.params.iter().map(|(k, _)| *k))
            .find(|k| *k == x.get_ref())
            .ok_or_else(|| {
                self.src.error(
                    self.src.line(x),
                    format!("plot_x: no run has a parameter '{}'", x.get_ref()),
                )
            })
    }

    /// The index of `target` among `runs`, or an error at `line` saying what to add.
    fn find_run(&self, runs: &[Run], target: &Run, line: usize, what: &str) -> Result<usize> {
        runs.iter()
            .position(|r| r.method == target.method && r.params == target.params)
            .ok_or_else(|| {
                self.src.error(
                    line,
                    format!(
                        "{what} is `{}`, which is not one of the experiment's runs; list it in an [[approximations]] entry",
                        target.label()
                    ),
                )
            })
    }

    /// An `[[attribution]]` table: `run = { method = …, … }` and its chain of `steps`, each
    /// swap applied to the previous run as a `baseline` is (see [`baseline_run`]).
    fn attribution(&self, a: &AttributionFile, runs: &[Run], ref_spp: u32) -> Result<Attribution> {
        let line = self.src.line(&a.run);
        let has_method = a
            .run
            .get_ref()
            .as_table()
            .is_some_and(|t| t.contains_key("method"));
        if !has_method {
            return Err(self.src.error(
                line,
                "attribution: `run` must be a table naming the method, e.g. run = { method = \"thesis\", n_exact = 5 }".into(),
            ));
        }
        let any: &'static dyn SweepMethod = &super::riemann::RIEMANN;
        let spec = self.baseline(any, &a.run)?;
        let empty = Run {
            method: spec.method.name(),
            params: Vec::new(),
            baseline: None,
        };
        let mut current = baseline_run(&empty, &spec, ref_spp);
        let first = self.find_run(runs, &current, line, "the attributed run")?;
        let mut steps = Vec::new();
        for (i, step) in a.steps.iter().enumerate() {
            let line = self.src.line(&step.swap);
            if step.swap.get_ref().as_str() == Some("reference") {
                if i + 1 != a.steps.len() {
                    return Err(self.src.error(
                        line,
                        "attribution: swap = \"reference\" ends the chain; it must be the last step".into(),
                    ));
                }
                steps.push(AttributionStep {
                    cause: step.cause.clone(),
                    run: None,
                });
                break;
            }
            let method = find_method(current.method).unwrap_or(any);
            let spec = self.baseline(method, &step.swap)?;
            current = baseline_run(&current, &spec, ref_spp);
            let what = format!("the run without {}", step.cause);
            let run = self.find_run(runs, &current, line, &what)?;
            steps.push(AttributionStep {
                cause: step.cause.clone(),
                run: Some(run),
            });
        }
        Ok(Attribution { run: first, steps })
    }
}

/// One value of parameter `p`: a count ≥ `p.min`, or `"all"` where `p` accepts it.
fn one_value(p: &SweepParam, v: &toml::Value) -> std::result::Result<ParamValue, String> {
    let expected = || {
        let range = format!("expected whole numbers from {} to {}", p.min, p.max);
        if p.accepts_all {
            format!("{range} or \"all\"")
        } else {
            range
        }
    };
    match v {
        toml::Value::String(s) if p.accepts_all && s == "all" => Ok(ParamValue::All),
        toml::Value::Integer(n) if *n >= p.min as i64 && *n <= p.max as i64 => {
            Ok(ParamValue::Count(*n as u32))
        }
        other => Err(format!("{}, got {other}", expected())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sweep::conventions::Normalize;

    fn parse(text: &str) -> Result<Experiment> {
        Experiment::parse(text, Path::new("dir/exp.toml"))
    }

    #[test]
    fn runs_are_the_cartesian_product_in_declared_order() {
        let e = parse(
            "scene = \"s.toml\"\n[reference]\nspp = 2\n[[approximations]]\nmethod = \"thesis\"\nn_exact = [1, 2, 3]\nsamples = [10, 100]\n[[approximations]]\nmethod = \"riemann\"\nsamples = 5\n",
        )
        .unwrap();
        assert_eq!(e.scene, Path::new("dir/s.toml"));
        assert_eq!(e.runs.len(), 7);
        assert_eq!(e.runs[0].label(), "thesis samples=10 n_exact=1");
        assert_eq!(e.runs[5].label(), "thesis samples=100 n_exact=3");
        // spp defaults to the reference's.
        assert_eq!(e.runs[6].label(), "riemann samples=5 spp=2");
        assert_eq!(e.runs[6].values(), vec![("samples", 5), ("spp", 2)]);
    }

    #[test]
    fn splats_rasteriser_constants_stay_out_of_labels_at_their_defaults() {
        let e = parse(
            "scene = \"s.toml\"\n[[approximations]]\nmethod = \"splat\"\n[[approximations]]\nmethod = \"splat\"\nalpha_cap = 999000\nnear = [10000]\n",
        )
        .unwrap();
        assert_eq!(e.runs[0].label(), "splat");
        assert_eq!(e.runs[0].file_stem(), "splat");
        assert_eq!(e.runs[1].label(), "splat alpha_cap=999000 near=10000");
    }

    #[test]
    fn all_is_a_value_of_n_exact_only() {
        let e = parse("scene = \"s.toml\"\n[[approximations]]\nmethod = \"thesis\"\nsamples = [4]\nn_exact = [2, \"all\"]\n").unwrap();
        assert_eq!(e.runs[1].param("n_exact"), Some(ParamValue::All));
        assert_eq!(e.runs[1].label(), "thesis samples=4 n_exact=all");
        assert_eq!(e.runs[1].file_stem(), "thesis_samples_4_n_exact_all");
        assert_eq!(e.runs[1].values()[1], ("n_exact", u32::MAX));
        let e = parse(
            "scene = \"s.toml\"\n[[approximations]]\nmethod = \"thesis\"\nn_exact = \"all\"\n",
        )
        .unwrap();
        assert_eq!(e.runs[0].label(), "thesis samples=100 n_exact=all");
        let err = parse(
            "scene = \"s.toml\"\n[[approximations]]\nmethod = \"thesis\"\nsamples = \"all\"\n",
        )
        .unwrap_err()
        .to_string();
        assert!(
            err.starts_with(
                "dir/exp.toml:4: samples: expected whole numbers from 1 to 16777216, got \"all\""
            ),
            "{err}"
        );
        let err = parse(
            "scene = \"s.toml\"\n[[approximations]]\nmethod = \"riemann\"\nsamples = [1, 0]\n",
        )
        .unwrap_err()
        .to_string();
        assert!(
            err.contains("exp.toml:4:") && err.contains("got 0"),
            "{err}"
        );
    }

    #[test]
    fn unknown_methods_and_parameters_name_the_line_and_the_valid_ones() {
        let err =
            parse("scene = \"s.toml\"\n[[approximations]]\nmethod = \"magic\"\nsamples = [1]\n")
                .unwrap_err()
                .to_string();
        assert!(
            err.starts_with("dir/exp.toml:3: unknown method \"magic\""),
            "{err}"
        );
        assert!(
            err.contains("riemann, thesis-cpu, emission, opaque, thesis"),
            "{err}"
        );
        let err = parse("scene = \"s.toml\"\n[[approximations]]\nmethod = \"riemann\"\nsamples = [1]\nsample = [1]\n").unwrap_err().to_string();
        assert!(err.starts_with("dir/exp.toml:5: method riemann has no parameter 'sample'; its parameters are samples, spp"), "{err}");
        let err = parse("scene = \"s.toml\"\n[[approximations]]\nsamples = [1]\n")
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("dir/exp.toml:3:") && err.contains("needs `method"),
            "{err}"
        );
        let err =
            parse("scene = \"s.toml\"\nbogus = 1\n[[approximations]]\nmethod = \"riemann\"\n")
                .unwrap_err()
                .to_string();
        assert!(
            err.starts_with("dir/exp.toml:2:") && err.contains("bogus"),
            "{err}"
        );
        let e = parse("scene = \"s.toml\"\n[[approximations]]\nmethod = \"emission\"\n").unwrap();
        assert_eq!(e.runs[0].label(), "emission");
    }

    #[test]
    fn baselines_name_runs_of_the_experiment() {
        let e = parse("scene = \"s.toml\"\n[[approximations]]\nmethod = \"thesis\"\nsamples = [10, 100]\nn_exact = [1, \"all\"]\nbaseline = { n_exact = \"all\" }\n[[approximations]]\nmethod = \"riemann\"\nsamples = [10]\nbaseline = { method = \"thesis\", samples = 100 }\n").unwrap();
        let b: Vec<Option<usize>> = e.runs.iter().map(|r| r.baseline).collect();
        // thesis 10/1 → 10/all, 10/all → itself, 100/1 → 100/all; riemann → thesis 100/all.
        assert_eq!(b, vec![Some(1), Some(1), Some(3), Some(3), Some(3)]);
        let err = parse("scene = \"s.toml\"\n[[approximations]]\nmethod = \"thesis\"\nn_exact = [1]\nbaseline = { n_exact = 2 }\n").unwrap_err().to_string();
        assert!(err.starts_with("dir/exp.toml:5: the baseline of `thesis samples=100 n_exact=1` is `thesis samples=100 n_exact=2`"), "{err}");
        let err = parse(
            "scene = \"s.toml\"\n[[approximations]]\nmethod = \"thesis\"\nbaseline = { n = 2 }\n",
        )
        .unwrap_err()
        .to_string();
        assert!(
            err.contains("exp.toml:4:") && err.contains("no parameter 'n'"),
            "{err}"
        );
    }

    const CHAIN_RUNS: &str = "scene = \"s.toml\"\nplot_x = \"samples\"\n[[approximations]]\nmethod = \"thesis\"\nn_exact = [5, \"all\"]\n[[approximations]]\nmethod = \"thesis-cpu\"\nn_exact = [5, \"all\"]\n[[approximations]]\nmethod = \"riemann\"\n";

    #[test]
    fn attributions_are_chains_of_the_experiments_runs() {
        let text = format!("{CHAIN_RUNS}[[attribution]]\nrun = {{ method = \"thesis\", n_exact = 5 }}\nsteps = [\n  {{ cause = \"float32\", swap = {{ method = \"thesis-cpu\" }} }},\n  {{ cause = \"n_exact\", swap = {{ n_exact = \"all\" }} }},\n  {{ cause = \"overlap\", swap = {{ method = \"riemann\" }} }},\n  {{ cause = \"sampling\", swap = \"reference\" }},\n]\n");
        let e = parse(&text).unwrap();
        assert_eq!(e.plot_x, Some("samples"));
        // Runs: thesis 5, thesis all, thesis-cpu 5, thesis-cpu all, riemann.
        let a = &e.attributions[0];
        assert_eq!(a.run, 0);
        let chain: Vec<(&str, Option<usize>)> =
            a.steps.iter().map(|s| (s.cause.as_str(), s.run)).collect();
        assert_eq!(
            chain,
            vec![
                ("float32", Some(2)),
                ("n_exact", Some(3)),
                ("overlap", Some(4)),
                ("sampling", None)
            ]
        );
        let err = parse(&format!("{CHAIN_RUNS}[[attribution]]\nrun = {{ method = \"thesis\", n_exact = 3 }}\nsteps = []\n")).unwrap_err().to_string();
        assert!(
            err.starts_with(
                "dir/exp.toml:12: the attributed run is `thesis samples=100 n_exact=3`"
            ),
            "{err}"
        );
        let err = parse(&format!("{CHAIN_RUNS}[[attribution]]\nrun = {{ method = \"thesis\", n_exact = 5 }}\nsteps = [{{ cause = \"x\", swap = \"reference\" }}, {{ cause = \"y\", swap = {{ n_exact = 1 }} }}]\n")).unwrap_err().to_string();
        assert!(
            err.contains("exp.toml:13:") && err.contains("must be the last step"),
            "{err}"
        );
        let err = parse(&format!(
            "{CHAIN_RUNS}[[attribution]]\nrun = {{ n_exact = 5 }}\nsteps = []\n"
        ))
        .unwrap_err()
        .to_string();
        assert!(
            err.contains("exp.toml:12:") && err.contains("naming the method"),
            "{err}"
        );
        let err = parse(&CHAIN_RUNS.replace("plot_x = \"samples\"", "plot_x = \"spp2\""))
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("dir/exp.toml:2: plot_x: no run has a parameter 'spp2'"),
            "{err}"
        );
    }

    #[test]
    fn conventions_are_read_in_order_and_checked_at_their_line() {
        let runs = "scene = \"s.toml\"\n[[approximations]]\nmethod = \"thesis-cpu\"\nn_exact = [1, \"all\"]\nbaseline = { n_exact = \"all\" }\n";
        let e = parse(&format!("{runs}[[conventions]]\nname = \"a\"\nnormalize = \"channel-max\"\nquantize = 8\n[[conventions]]\nname = \"b\"\n")).unwrap();
        let got: Vec<_> = e
            .conventions
            .iter()
            .map(|c| (c.name.as_str(), c.normalize, c.quantize))
            .collect();
        assert_eq!(
            got,
            [
                ("a", Normalize::ChannelMax, Some(8)),
                ("b", Normalize::None, None)
            ]
        );
        // Each case's table starts at line 6 (after the five lines of runs).
        let cases = [
            (
                "name = \"a\"\nquantize = 0\n",
                "quantize must be between 1 and 24 bits, got 0",
            ),
            (
                "name = \"a\"\nquantize = 25\n",
                "quantize must be between 1 and 24 bits, got 25",
            ),
            ("name = \" \"\n", "name must not be empty"),
        ];
        for (table, message) in cases {
            let err = parse(&format!("{runs}[[conventions]]\n{table}"))
                .unwrap_err()
                .to_string();
            assert!(
                err.contains("exp.toml:6") && err.contains(message),
                "{table}: {err}"
            );
        }
        let twice = format!("{runs}[[conventions]]\nname = \"a\"\n[[conventions]]\nname = \"a\"\n");
        let err = parse(&twice).unwrap_err().to_string();
        assert!(
            err.contains("exp.toml:8") && err.contains("'a' is given twice"),
            "{err}"
        );
        let unknown = format!("{runs}[[conventions]]\nname = \"a\"\nnormalize = \"mean\"\n");
        let err = parse(&unknown).unwrap_err().to_string();
        assert!(
            err.contains("exp.toml:8") && err.contains("channel-max"),
            "{err}"
        );
        let no_baseline = "scene = \"s.toml\"\n[[approximations]]\nmethod = \"thesis-cpu\"\nn_exact = 1\n[[conventions]]\nname = \"a\"\n";
        let err = parse(no_baseline).unwrap_err().to_string();
        assert!(
            err.contains("exp.toml:5")
                && err.contains("no [[approximations]] entry has a `baseline`"),
            "{err}"
        );
    }

    #[test]
    fn an_experiment_without_runs_is_an_error() {
        let err =
            parse("scene = \"s.toml\"\n[[approximations]]\nmethod = \"riemann\"\nsamples = []\n")
                .unwrap_err()
                .to_string();
        assert!(err.contains("no approximation runs"), "{err}");
    }

    #[test]
    fn global_values_are_checked_at_their_line_before_anything_runs() {
        let runs = "[[approximations]]\nmethod = \"riemann\"\nsamples = 1\n";
        let cases = [
            ("size = [0, 16]\n", 2, "size: image size must be between 1"),
            (
                "data_range = -1.0\n",
                2,
                "data_range must be a finite number > 0, got -1",
            ),
            (
                "data_range = nan\n",
                2,
                "data_range must be a finite number > 0, got NaN",
            ),
            (
                "[reference]\nspp = 0\n",
                2,
                "reference.spp must be between 1 and 64, got 0",
            ),
            (
                "[reference]\ntol = -1e-5\n",
                2,
                "reference.tol must be a finite number > 0",
            ),
        ];
        for (globals, line, message) in cases {
            let text = format!("scene = \"s.toml\"\n{globals}{runs}");
            let err = parse(&text).unwrap_err().to_string();
            assert!(err.starts_with(&format!("dir/exp.toml:{line}: ")), "{err}");
            assert!(err.contains(message), "{err}");
        }
        let err =
            parse("scene = \"s.toml\"\n[[approximations]]\nmethod = \"riemann\"\nspp = [65]\n")
                .unwrap_err()
                .to_string();
        assert!(
            err.contains("dir/exp.toml:4: spp: expected whole numbers from 1 to 64, got 65"),
            "{err}"
        );
    }

    #[test]
    fn a_product_of_lists_beyond_max_runs_is_refused_at_its_entry() {
        let list: Vec<String> = (1..=101).map(|n| n.to_string()).collect();
        let list = list.join(", ");
        let text = format!(
            "scene = \"s.toml\"\n[[approximations]]\nmethod = \"riemann\"\nsamples = [{list}]\n\n[[approximations]]\nmethod = \"thesis\"\nsamples = [{list}]\nn_exact = [{list}]\n"
        );
        let err = parse(&text).unwrap_err().to_string();
        assert!(err.starts_with("dir/exp.toml:7: "), "{err}");
        assert!(err.contains("more than 10000 runs"), "{err}");
    }
}
