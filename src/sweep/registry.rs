//! The methods a sweep can run, by name: the CPU methods and every GPU method of the
//! approximation registry. Experiment files and messages go through [`find_method`] and
//! [`method_names`]; the methods themselves implement `method::SweepMethod` and know nothing
//! of this table.

use super::method::SweepMethod;

/// The CPU methods: `riemann` and `thesis-cpu`.
fn cpu_methods() -> [&'static dyn SweepMethod; 2] {
    [&super::riemann::RIEMANN, &super::thesis_cpu::THESIS_CPU]
}

/// The method named `name`: the CPU methods (`riemann`, `thesis-cpu`), then every method of
/// the approximation registry.
pub fn find_method(name: &str) -> Option<&'static dyn SweepMethod> {
    if let Some(m) = cpu_methods().into_iter().find(|m| m.name() == name) {
        return Some(m);
    }
    super::gpu::gpu_methods()
        .iter()
        .find(|m| m.name() == name)
        .map(|m| m as &'static dyn SweepMethod)
}

/// The names [`find_method`] knows, for error messages and docs.
pub fn method_names() -> Vec<&'static str> {
    cpu_methods()
        .into_iter()
        .map(|m| m.name())
        .chain(super::gpu::gpu_methods().iter().map(|m| m.name()))
        .collect()
}
