//! What a method parameter is (docs/design.md §4): its name, default, range and meaning, as
//! each method of the registry declares it.

/// `n_exact` meaning "every particle on the ray" (`--n-exact all`).
pub const N_EXACT_ALL: u32 = u32::MAX;

/// One parameter of a method: its name, default, valid range and meaning.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ParamSpec {
    /// Name on the command line (`--param NAME=VALUE`), in sweeps and in WGSL (`PARAM_NAME`).
    pub name: &'static str,
    /// Whether a sweep's run labels and file names leave it out at its default value: the
    /// parameters a method gains after its runs were named (splat's rasteriser constants), so
    /// that those runs keep their names.
    pub quiet_default: bool,
    pub default: u32,
    /// Smallest valid value.
    pub min: u32,
    /// Largest valid value ([`N_EXACT_ALL`] where "all" is meaningful).
    pub max: u32,
    /// One line: what it does.
    pub doc: &'static str,
}

impl ParamSpec {
    /// A value as people write it: "all" for [`N_EXACT_ALL`] where that is the maximum.
    pub fn show(&self, value: u32) -> String {
        if value == N_EXACT_ALL && self.max == N_EXACT_ALL {
            "all".into()
        } else {
            value.to_string()
        }
    }

    /// "1..=16777216", "0..=all".
    pub fn range(&self) -> String {
        format!("{}..={}", self.show(self.min), self.show(self.max))
    }
}
