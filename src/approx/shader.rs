//! WGSL programs: the declarations generated from the CPU–GPU contract
//! ([`super::wgsl::wgsl_declarations`]), the method's parameter slot names, the prelude
//! `shaders/common.wgsl`, one method file and the entry point `shaders/entry.wgsl`,
//! concatenated, then parsed and validated with naga before any pipeline exists (docs/design.md §4). Errors name the file the offending line came from and its line in
//! *that* file, so a user's mistake points at the user's line, not at the concatenation.

use crate::error::{PgtError, Result};
use std::borrow::Cow;

/// The prelude every method is appended to.
pub const COMMON_WGSL: &str = include_str!("../../shaders/common.wgsl");
/// The compute entry point `pgt_main`, appended after the method.
pub const ENTRY_WGSL: &str = include_str!("../../shaders/entry.wgsl");
/// A WGSL file shared by several programs and included where a program needs it (WGSL has no
/// imports): the program declares what the module leaves to it (its header says what).
#[derive(Debug, Clone, Copy)]
pub struct WgslModule {
    /// The file's path in the repository, for messages.
    pub path: &'static str,
    pub text: &'static str,
    /// The functions generated for the file (`approx::wgsl_generic`), appended to its text.
    pub generated: fn() -> String,
}

impl WgslModule {
    /// The module as a part of a program: the file, then its generated functions (the file's
    /// lines keep their numbers in messages).
    pub fn part(&self) -> ShaderPart {
        ShaderPart {
            name: self.path.into(),
            text: Cow::Owned(format!("{}{}", self.text, (self.generated)())),
        }
    }
}

/// `shaders/nearest_events.wgsl`: the batch of the nearest events along a ray and the BVH
/// traversal that fills it (`ever`, `gauss-ray` and the GPU reference).
pub const NEAREST_EVENTS: WgslModule = WgslModule {
    path: "shaders/nearest_events.wgsl",
    text: include_str!("../../shaders/nearest_events.wgsl"),
    generated: super::wgsl_generic::nearest_events_functions,
};

/// The name the entry point file has in messages.
const ENTRY_FILE: &str = "shaders/entry.wgsl";
/// Name of the compute entry point.
pub const ENTRY_POINT: &str = "pgt_main";

/// How messages name the generated declarations (an error there is pgt's bug, not the user's).
pub const GENERATED_CONTRACT: &str = "<generated from src/approx/contract.rs>";
/// How messages name the prelude's generated functions.
pub const GENERATED_FUNCTIONS: &str = "<generated from src/approx/wgsl_generic.rs>";
/// How messages name the generated parameter slot constants.
pub const GENERATED_PARAMS: &str = "<generated parameter slots>";

/// The generated contract, `shaders/common.wgsl` and the functions generated for it: everything
/// a method can use.
pub fn prelude_parts() -> Vec<ShaderPart> {
    vec![
        ShaderPart {
            name: GENERATED_CONTRACT.into(),
            text: Cow::Owned(super::wgsl::wgsl_declarations()),
        },
        ShaderPart {
            name: "shaders/common.wgsl".into(),
            text: Cow::Borrowed(COMMON_WGSL),
        },
        ShaderPart {
            name: GENERATED_FUNCTIONS.into(),
            text: Cow::Owned(super::wgsl_generic::prelude_functions()),
        },
    ]
}

/// The prelude as one text (generated contract + `shaders/common.wgsl`), e.g. for naga.
pub fn prelude_source() -> String {
    ShaderProgram::from_parts(prelude_parts())
        .source()
        .to_string()
}

/// One source file of a program.
#[derive(Debug, Clone)]
pub struct ShaderPart {
    /// How messages name it (a path).
    pub name: String,
    pub text: Cow<'static, str>,
}

/// A complete WGSL program and where each part starts in it.
#[derive(Debug, Clone)]
pub struct ShaderProgram {
    parts: Vec<ShaderPart>,
    /// Byte offset of each part in `source`.
    starts: Vec<usize>,
    source: String,
}

/// A position in one part: file name, 1-based line and column.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SourcePosition {
    pub file: String,
    pub line: usize,
    pub column: usize,
}

impl ShaderProgram {
    /// Generated contract + parameter slots + prelude + `method` + entry point.
    /// `param_names`: the method's parameters in slot order (`PARAM_<NAME>` constants).
    pub fn with_method<'a>(
        method: ShaderPart,
        param_names: impl IntoIterator<Item = &'a str>,
    ) -> ShaderProgram {
        ShaderProgram::with_method_and_modules(method, &[], param_names)
    }

    /// [`ShaderProgram::with_method`] with the shared `modules` the method uses, before it.
    pub fn with_method_and_modules<'a>(
        method: ShaderPart,
        modules: &[WgslModule],
        param_names: impl IntoIterator<Item = &'a str>,
    ) -> ShaderProgram {
        let mut parts = prelude_parts();
        parts.push(ShaderPart {
            name: GENERATED_PARAMS.into(),
            text: Cow::Owned(super::wgsl::param_declarations(param_names)),
        });
        parts.extend(modules.iter().map(WgslModule::part));
        parts.push(method);
        parts.push(ShaderPart {
            name: ENTRY_FILE.into(),
            text: Cow::Borrowed(ENTRY_WGSL),
        });
        ShaderProgram::from_parts(parts)
    }

    /// Concatenates parts, each ending with a newline so lines never merge across files.
    pub fn from_parts(parts: Vec<ShaderPart>) -> ShaderProgram {
        let mut source = String::new();
        let mut starts = Vec::with_capacity(parts.len());
        for part in &parts {
            starts.push(source.len());
            source.push_str(&part.text);
            if !part.text.ends_with('\n') {
                source.push('\n');
            }
        }
        ShaderProgram {
            parts,
            starts,
            source,
        }
    }

    /// The concatenated WGSL.
    pub fn source(&self) -> &str {
        &self.source
    }

    /// Maps a byte offset of the concatenated source to (file, line, column) of its part.
    pub fn position(&self, offset: usize) -> SourcePosition {
        let offset = offset.min(self.source.len());
        let k = self.starts.iter().rposition(|&s| s <= offset).unwrap_or(0);
        let start = self.starts.get(k).copied().unwrap_or(0);
        let prefix = self.source.get(start..offset).unwrap_or("");
        let line = prefix.matches('\n').count() + 1;
        let line_start = prefix.rfind('\n').map_or(0, |p| p + 1);
        SourcePosition {
            file: self
                .parts
                .get(k)
                .map_or_else(String::new, |p| p.name.clone()),
            line,
            column: prefix.len() - line_start + 1,
        }
    }

    fn describe_span(&self, span: naga::Span) -> Option<String> {
        let range = span.to_range()?;
        let p = self.position(range.start);
        let text = self.source.get(range).unwrap_or("");
        let snippet: String = text.lines().next().unwrap_or("").chars().take(60).collect();
        Some(if snippet.is_empty() {
            format!("{}:{}:{}", p.file, p.line, p.column)
        } else {
            format!("{}:{}:{} (`{}`)", p.file, p.line, p.column, snippet)
        })
    }

    /// `file:line:column: ` of the source offset an error points at. pgt's entry point only
    /// calls the method's `shade`, so an error there is the method's: it is blamed on the line
    /// of the method's `fn shade`, saying what the entry point expects.
    fn blame(&self, offset: usize) -> String {
        let p = self.position(offset);
        let entry = self.parts.len().checked_sub(1);
        let in_entry =
            entry.is_some_and(|k| self.parts[k].name == ENTRY_FILE && p.file == ENTRY_FILE);
        let method = self.parts.len().checked_sub(2).map(|k| (k, &self.parts[k]));
        match method {
            Some((k, part)) if in_entry => {
                let at = part.text.find("fn shade").unwrap_or(0);
                let m = self.position(self.starts[k] + at);
                format!(
                    "{}:{}:{}: `shade` must be `fn shade(ray: Ray, pixel: vec2<u32>) -> vec3<f32>` \
                     (pgt's entry point {}:{} calls it so): ",
                    m.file, m.line, m.column, p.file, p.line
                )
            }
            _ => format!("{}:{}:{}: ", p.file, p.line, p.column),
        }
    }

    /// Parses and validates the program with naga; errors name the file and line.
    pub fn validate(&self) -> Result<naga::Module> {
        self.validate_with(naga::valid::Capabilities::default())
    }

    /// [`ShaderProgram::validate`] allowing `capabilities` (the GPU reference's f64).
    pub fn validate_with(&self, capabilities: naga::valid::Capabilities) -> Result<naga::Module> {
        let module = naga::front::wgsl::parse_str(&self.source).map_err(|e| {
            let mut msg = String::new();
            let first = e.labels().find_map(|(span, _)| span.to_range());
            if let Some(range) = first {
                msg += &self.blame(range.start);
            }
            msg += &format!("WGSL error: {}", e.message());
            for (span, label) in e.labels() {
                if let Some(at) = self.describe_span(span) {
                    if !label.is_empty() {
                        msg += &format!("\n  {at}: {label}");
                    }
                }
            }
            for note in e.notes() {
                msg += &format!("\n  note: {note}");
            }
            PgtError::Gpu(msg)
        })?;
        let mut validator =
            naga::valid::Validator::new(naga::valid::ValidationFlags::all(), capabilities);
        validator.validate(&module).map_err(|e| {
            let mut msg = String::new();
            // The last span is the most specific (the expression, after the function that holds it).
            let first = e.spans().filter_map(|(span, _)| span.to_range()).last();
            if let Some(range) = first {
                msg += &self.blame(range.start);
            }
            // The error chain names the function, expression and reason.
            msg += &format!("WGSL validation error: {}", e.as_inner());
            let mut source = std::error::Error::source(e.as_inner());
            while let Some(s) = source {
                msg += &format!(": {s}");
                source = s.source();
            }
            for (span, label) in e.spans() {
                if let Some(at) = self.describe_span(*span) {
                    msg += &format!("\n  {at}: {label}");
                }
            }
            PgtError::Gpu(msg)
        })?;
        Ok(module)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn part(name: &str, text: &'static str) -> ShaderPart {
        ShaderPart {
            name: name.into(),
            text: Cow::Borrowed(text),
        }
    }

    #[test]
    fn positions_are_relative_to_each_part() {
        let p =
            ShaderProgram::from_parts(vec![part("a.wgsl", "x\ny\n"), part("b.wgsl", "one\ntwo")]);
        let at = |needle: &str| p.position(p.source().find(needle).unwrap());
        assert_eq!(
            at("y"),
            SourcePosition {
                file: "a.wgsl".into(),
                line: 2,
                column: 1
            }
        );
        assert_eq!(
            at("two"),
            SourcePosition {
                file: "b.wgsl".into(),
                line: 2,
                column: 1
            }
        );
        assert_eq!(
            at("wo"),
            SourcePosition {
                file: "b.wgsl".into(),
                line: 2,
                column: 2
            }
        );
    }

    #[test]
    fn shipped_methods_validate() {
        for method in crate::approx::methods::METHODS {
            let prog = ShaderProgram::with_method_and_modules(
                part(method.name(), method.wgsl()),
                method.modules(),
                method.params().iter().map(|p| p.name),
            );
            if let Err(e) = prog.validate() {
                panic!("{}: {e}", method.name());
            }
        }
        for (name, text) in [
            (
                "examples/centre_shadow",
                include_str!("../../shaders/examples/centre_shadow.wgsl"),
            ),
            (
                "examples/no_shadows",
                include_str!("../../shaders/examples/no_shadows.wgsl"),
            ),
        ] {
            let names = crate::approx::params::USER_PARAMS.iter().map(|p| p.name);
            let prog = ShaderProgram::with_method(part(name, text), names);
            if let Err(e) = prog.validate() {
                panic!("{name}: {e}");
            }
        }
    }

    #[test]
    fn an_error_in_the_method_names_the_method_file_and_its_line() {
        let prog = ShaderProgram::with_method(part(
            "mine.wgsl",
            "// line 1\nfn shade(ray: Ray, pixel: vec2<u32>) -> vec3<f32> {\n    return vec3<f32>(undefined_thing);\n}\n",
        ), []);
        let err = prog.validate().unwrap_err().to_string();
        assert!(err.starts_with("mine.wgsl:3:"), "{err}");
        assert!(err.contains("undefined_thing"), "{err}");
    }

    #[test]
    fn a_type_error_found_by_the_validator_points_at_the_method_line() {
        let prog = ShaderProgram::with_method(part(
            "mine.wgsl",
            "fn shade(ray: Ray, pixel: vec2<u32>) -> vec3<f32> {\n    let a = 1.0;\n    return a;\n}\n",
        ), []);
        let err = prog.validate().unwrap_err().to_string();
        assert!(err.contains("mine.wgsl:"), "{err}");
    }
}
