//! Which method runs ([`Method`]: one of the registry's or a user's file) and the parameter
//! values chosen for it by name ([`ApproxParams`]), validated against the method's
//! [`ParamSpec`]s (docs/design.md §4: "methods, chosen by name, each a documented set of
//! parameters"). The values travel to the GPU in `GpuFrame::params`, slot k for the k-th
//! parameter, so a new parameter needs no new field anywhere.

use super::contract::PARAM_SLOTS;
use super::methods::{self, ApproxMethod};
use super::param_spec::{ParamSpec, N_EXACT_ALL};
use super::shader::{ShaderPart, ShaderProgram};
use crate::error::{PgtError, Result};
use crate::scene::Scene;
use std::borrow::Cow;
use std::path::PathBuf;

/// The parameters a user shader (`--shader`) always has, so that `PARAM_SAMPLES` and
/// `PARAM_N_EXACT` exist for it as they do for `thesis`; `--param` adds more.
pub const USER_PARAMS: &[ParamSpec] = &[
    ParamSpec {
        name: "samples",
        quiet_default: false,
        default: 100,
        min: 0,
        max: u32::MAX,
        doc: "for the user's method (slot PARAM_SAMPLES)",
    },
    ParamSpec {
        name: "n_exact",
        quiet_default: false,
        default: N_EXACT_ALL,
        min: 0,
        max: N_EXACT_ALL,
        doc: "for the user's method (slot PARAM_N_EXACT)",
    },
];

/// Which approximation runs: one of the registry's ([`methods::METHODS`]) or a user's file.
#[derive(Clone)]
pub enum Method {
    Builtin(&'static dyn ApproxMethod),
    /// A user's WGSL file defining `shade` (docs/user-shaders.md).
    User(PathBuf),
}

impl std::fmt::Debug for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.name())
    }
}

impl PartialEq for Method {
    fn eq(&self, other: &Method) -> bool {
        match (self, other) {
            (Method::Builtin(a), Method::Builtin(b)) => a.name() == b.name(),
            (Method::User(a), Method::User(b)) => a == b,
            _ => false,
        }
    }
}

impl Method {
    /// The registered method of that name; the error lists the names.
    pub fn named(name: &str) -> Result<Method> {
        methods::find_method(name)
            .map(Method::Builtin)
            .ok_or_else(|| {
                PgtError::Usage(format!(
                    "unknown approximation method '{name}'; the methods are: {}",
                    methods::names().join(", ")
                ))
            })
    }

    /// The method a scene gets when none is named ([`methods::default_for`]).
    pub fn default_for(scene: &Scene) -> Method {
        Method::Builtin(methods::default_for(scene))
    }

    /// A short name for summaries.
    pub fn name(&self) -> String {
        match self {
            Method::Builtin(m) => m.name().into(),
            Method::User(p) => format!("user shader {}", p.display()),
        }
    }

    /// Refuses combinations that have no meaning, with a message that says what to do (a user
    /// shader takes any scene: it says itself what it computes).
    pub fn check_scene(&self, scene: &Scene) -> Result<()> {
        match self {
            Method::Builtin(m) => m.check_scene(scene),
            // A user shader is given only constant-density scenes (docs/user-shaders.md does
            // not describe `Particle.profile`).
            Method::User(_) => super::methods::check_profile("user-shader", false, scene),
        }
    }

    /// What it needs made on the CPU before the dispatch (a user shader: nothing).
    pub fn preparation(&self) -> super::methods::Preparation {
        match self {
            Method::Builtin(m) => m.preparation(),
            Method::User(_) => super::methods::Preparation::default(),
        }
    }

    /// The parameters this method takes without `--param` additions.
    pub fn specs(&self) -> &'static [ParamSpec] {
        match self {
            Method::Builtin(m) => m.params(),
            Method::User(_) => USER_PARAMS,
        }
    }

    /// The complete program with the parameter slots named after `values` (in slot order).
    pub fn program(&self, values: &[(String, u32)]) -> Result<ShaderProgram> {
        let (part, modules) = match self {
            Method::Builtin(m) => (
                ShaderPart {
                    name: m.wgsl_path().into(),
                    text: Cow::Borrowed(m.wgsl()),
                },
                m.modules(),
            ),
            Method::User(path) => (super::user_shader::load(path)?, &[][..]),
        };
        Ok(ShaderProgram::with_method_and_modules(
            part,
            modules,
            values.iter().map(|(n, _)| n.as_str()),
        ))
    }
}

/// Everything a GPU approximation run needs besides the scene: the library interface that
/// `pgt approx` and `pgt sweep` share.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ApproxParams {
    /// `None`: [`Method::default_for`] the scene.
    pub method: Option<Method>,
    /// Parameter values by name, as chosen; the others take their defaults. Checked against the
    /// method's [`ParamSpec`]s by [`ApproxParams::resolve`].
    pub values: Vec<(String, u32)>,
    /// Case-insensitive substring of the adapter name (`--adapter`).
    pub adapter: Option<String>,
}

impl ApproxParams {
    /// The registered method `name` with these parameter values, checked at once (unknown
    /// method, unknown parameter, value out of range: an error that lists what is valid). The
    /// sweep calls this for any method and any of its parameters.
    pub fn for_method(name: &str, values: &[(&str, u32)]) -> Result<ApproxParams> {
        let params = ApproxParams {
            method: Some(Method::named(name)?),
            values: values.iter().map(|(n, v)| (n.to_string(), *v)).collect(),
            adapter: None,
        };
        if let Some(m) = &params.method {
            params.resolve(m)?;
        }
        Ok(params)
    }

    /// The value chosen for `name`, if any (not the default).
    pub fn value(&self, name: &str) -> Option<u32> {
        self.values
            .iter()
            .rev()
            .find(|(n, _)| n == name)
            .map(|(_, v)| *v)
    }

    /// Every parameter of `method` with its value (chosen or default), in slot order. A user
    /// method also gets each chosen name it does not have yet (`--param`).
    pub fn resolve(&self, method: &Method) -> Result<Vec<(String, u32)>> {
        let specs = method.specs();
        let mut out: Vec<(String, u32)> = specs
            .iter()
            .map(|s| (s.name.to_string(), s.default))
            .collect();
        for (name, value) in &self.values {
            match specs.iter().position(|s| s.name == name) {
                Some(k) => {
                    let s = &specs[k];
                    if *value < s.min || *value > s.max {
                        return Err(PgtError::Usage(format!(
                            "{}: parameter {name} = {} is out of its range {}",
                            method.name(),
                            s.show(*value),
                            s.range()
                        )));
                    }
                    out[k].1 = *value;
                }
                None if matches!(method, Method::User(_)) => {
                    if !is_identifier(name) {
                        return Err(PgtError::Usage(format!(
                            "parameter name '{name}' is not a WGSL identifier (letters, digits, _)"
                        )));
                    }
                    match out.iter_mut().find(|(n, _)| n == name) {
                        Some(slot) => slot.1 = *value,
                        None => out.push((name.clone(), *value)),
                    }
                }
                None => return Err(unknown_parameter(method, name)),
            }
        }
        if out.len() > PARAM_SLOTS {
            return Err(PgtError::Usage(format!(
                "{}: {} parameters, the frame has {PARAM_SLOTS} slots",
                method.name(),
                out.len()
            )));
        }
        Ok(out)
    }
}

fn unknown_parameter(method: &Method, name: &str) -> PgtError {
    let specs = method.specs();
    let valid = if specs.is_empty() {
        "it has none".to_string()
    } else {
        let list: Vec<String> = specs
            .iter()
            .map(|s| format!("{} ({}, default {})", s.name, s.range(), s.show(s.default)))
            .collect();
        format!("its parameters: {}", list.join(", "))
    };
    PgtError::Usage(format!(
        "method {} has no parameter '{name}'; {valid}",
        method.name()
    ))
}

fn is_identifier(name: &str) -> bool {
    let mut chars = name.chars();
    chars
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_fill_the_parameters_not_chosen() {
        let p = ApproxParams::for_method("thesis", &[("n_exact", 3)]).unwrap();
        let m = p.method.clone().unwrap();
        let v = p.resolve(&m).unwrap();
        assert_eq!(v, vec![("samples".into(), 100), ("n_exact".into(), 3)]);
    }

    #[test]
    fn an_unknown_parameter_names_the_method_and_its_parameters() {
        let e = ApproxParams::for_method("thesis", &[("sample", 3)])
            .unwrap_err()
            .to_string();
        assert!(e.contains("thesis") && e.contains("'sample'"), "{e}");
        assert!(
            e.contains("samples (1..=") && e.contains("n_exact (0..=all"),
            "{e}"
        );
        let e = ApproxParams::for_method("emission", &[("samples", 3)])
            .unwrap_err()
            .to_string();
        assert!(e.contains("emission") && e.contains("it has none"), "{e}");
    }

    #[test]
    fn out_of_range_values_and_unknown_methods_are_refused() {
        let e = ApproxParams::for_method("thesis", &[("samples", 0)])
            .unwrap_err()
            .to_string();
        assert!(e.contains("samples = 0") && e.contains("1..="), "{e}");
        let e = ApproxParams::for_method("nope", &[])
            .unwrap_err()
            .to_string();
        assert!(e.contains("'nope'") && e.contains("thesis"), "{e}");
    }

    #[test]
    fn user_methods_take_new_parameters_by_name() {
        let p = ApproxParams {
            method: Some(Method::User("x.wgsl".into())),
            values: vec![("radius_scale".into(), 7), ("samples".into(), 4)],
            adapter: None,
        };
        let v = p.resolve(p.method.as_ref().unwrap()).unwrap();
        assert_eq!(
            v,
            vec![
                ("samples".into(), 4),
                ("n_exact".into(), N_EXACT_ALL),
                ("radius_scale".into(), 7)
            ]
        );
        let bad = ApproxParams {
            values: vec![("not valid".into(), 1)],
            ..p
        };
        assert!(bad.resolve(bad.method.as_ref().unwrap()).is_err());
    }
}
