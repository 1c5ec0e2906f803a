//! VRML97 syntax (ISO/IEC 14772-1 §5, §4.8–4.9) to a node tree: nodes with generic field values,
//! `DEF`/`USE` resolved while parsing (a `USE` names the latest `DEF` before it), `PROTO`s
//! resolved while parsing too (an instance uses the latest definition of its name before it, so a
//! redefinition takes effect for later instances), `EXTERNPROTO` declarations remembered (their
//! instances cannot be expanded), `ROUTE`s skipped.
//!
//! Without a field schema a value is read by its shape: `[ … ]` (a list of numbers, strings or
//! nodes), a run of numbers (`translation 1 2 3`), a string, `TRUE`/`FALSE`, `NULL`, `IS name`, or
//! a node (`Type { … }`, `DEF n Type { … }`, `USE n`). Node types must be VRML97 nodes or PROTOs
//! declared before the use; anything else is an error at its line.

use super::lexer::{Tok, Token};
use crate::error::{PgtError, Result};
use std::collections::HashMap;
use std::path::Path;
use std::rc::Rc;

/// Deepest nesting of nodes and values the parser accepts.
pub const MAX_DEPTH: usize = 256;

/// The standard node types of VRML97 (ISO/IEC 14772-1 §6).
const VRML97_NODES: &[&str] = &[
    "Anchor",
    "Appearance",
    "AudioClip",
    "Background",
    "Billboard",
    "Box",
    "Collision",
    "Color",
    "ColorInterpolator",
    "Cone",
    "Coordinate",
    "CoordinateInterpolator",
    "Cylinder",
    "CylinderSensor",
    "DirectionalLight",
    "ElevationGrid",
    "Extrusion",
    "Fog",
    "FontStyle",
    "Group",
    "ImageTexture",
    "IndexedFaceSet",
    "IndexedLineSet",
    "Inline",
    "LOD",
    "Material",
    "MovieTexture",
    "NavigationInfo",
    "Normal",
    "NormalInterpolator",
    "OrientationInterpolator",
    "PixelTexture",
    "PlaneSensor",
    "PointLight",
    "PointSet",
    "PositionInterpolator",
    "ProximitySensor",
    "ScalarInterpolator",
    "Script",
    "Shape",
    "Sound",
    "Sphere",
    "SphereSensor",
    "SpotLight",
    "Switch",
    "Text",
    "TextureCoordinate",
    "TextureTransform",
    "TimeSensor",
    "TouchSensor",
    "Transform",
    "Viewpoint",
    "VisibilitySensor",
    "WorldInfo",
];

/// A field value, read by its shape.
#[derive(Debug, Clone)]
pub enum Value {
    /// Numbers (SFFloat, SFVec3f, SFRotation, MFFloat, …; booleans inside lists as 1/0).
    Nums(Vec<f64>),
    /// `TRUE` / `FALSE`.
    Bool(bool),
    /// SFString / MFString.
    Strs(Vec<String>),
    /// SFNode; `None` is `NULL`.
    Node(Option<Rc<Node>>),
    /// MFNode.
    Nodes(Vec<Rc<Node>>),
    /// `IS name` inside a PROTO body.
    Is(String),
    /// `[]`.
    Empty,
}

/// What a node's type name refers to.
#[derive(Debug, Clone)]
pub enum NodeKind {
    /// A VRML97 node.
    Builtin,
    /// An instance of a PROTO defined in the file.
    Proto(Rc<Proto>),
    /// An instance of an EXTERNPROTO (not expanded).
    Extern,
}

/// A node as written.
#[derive(Debug)]
pub struct Node {
    /// The type as written (`Transform`, a PROTO name).
    pub type_name: String,
    /// What the type name refers to.
    pub kind: NodeKind,
    /// Fields in file order (a later duplicate wins).
    pub fields: Vec<(String, Value)>,
    /// Line of the type name.
    pub line: usize,
}

impl Node {
    /// The value of a field as written (`None` if the node does not set it).
    pub fn field(&self, name: &str) -> Option<&Value> {
        self.fields
            .iter()
            .rev()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v)
    }
}

/// A PROTO declaration.
#[derive(Debug)]
pub struct Proto {
    /// The PROTO's name.
    pub name: String,
    /// Interface fields with their default values (events have none and are left out).
    pub fields: Vec<(String, Value)>,
    /// The body's root nodes; the first is the one the instance stands for.
    pub body: Vec<Rc<Node>>,
    /// Line of the `PROTO` keyword.
    pub line: usize,
}

#[derive(Debug, Clone)]
enum ProtoDef {
    Defined(Rc<Proto>),
    Extern,
    /// Its body is being parsed: an instance now would instantiate itself.
    BeingDefined(usize),
}

#[derive(Default)]
struct Scope {
    defs: HashMap<String, Rc<Node>>,
    protos: HashMap<String, ProtoDef>,
}

struct Parser<'a> {
    path: &'a Path,
    toks: &'a [Token],
    pos: usize,
    /// File scope first, then one per PROTO body being parsed. Lookups go inside-out (lenient:
    /// VRML97 gives PROTO bodies their own name space; falling back to the file's names accepts
    /// files that rely on them).
    scopes: Vec<Scope>,
}

/// Parses a token stream into the file's root nodes.
pub fn parse(path: &Path, toks: &[Token]) -> Result<Vec<Rc<Node>>> {
    let mut p = Parser {
        path,
        toks,
        pos: 0,
        scopes: vec![Scope::default()],
    };
    let mut roots = Vec::new();
    while p.peek().is_some() {
        p.statement(&mut roots, 0)?;
    }
    Ok(roots)
}

fn describe(t: Option<&Token>) -> String {
    match t.map(|t| &t.tok) {
        None => "the end of the file".into(),
        Some(Tok::LBrace) => "'{'".into(),
        Some(Tok::RBrace) => "'}'".into(),
        Some(Tok::LBracket) => "'['".into(),
        Some(Tok::RBracket) => "']'".into(),
        Some(Tok::Num(n)) => format!("the number {n}"),
        Some(Tok::Str(s)) => format!("the string \"{}\"", s.chars().take(40).collect::<String>()),
        Some(Tok::Id(s)) => format!("'{s}'"),
    }
}

impl<'a> Parser<'a> {
    fn peek(&self) -> Option<&'a Token> {
        self.toks.get(self.pos)
    }
    fn peek_id(&self) -> Option<&'a str> {
        match self.peek().map(|t| &t.tok) {
            Some(Tok::Id(s)) => Some(s.as_str()),
            _ => None,
        }
    }
    fn line(&self) -> usize {
        self.peek()
            .or_else(|| self.toks.last())
            .map_or(1, |t| t.line)
    }
    fn err(&self, msg: impl Into<String>) -> PgtError {
        PgtError::at_line(self.path, self.line(), msg)
    }
    fn expected(&self, what: &str) -> PgtError {
        self.err(format!("expected {what}, found {}", describe(self.peek())))
    }
    fn expect(&mut self, tok: Tok, what: &str) -> Result<()> {
        if self.peek().map(|t| &t.tok) == Some(&tok) {
            self.pos += 1;
            Ok(())
        } else {
            Err(self.expected(what))
        }
    }
    fn id(&mut self, what: &str) -> Result<String> {
        match self.peek().map(|t| &t.tok) {
            Some(Tok::Id(s)) => {
                let s = s.clone();
                self.pos += 1;
                Ok(s)
            }
            _ => Err(self.expected(what)),
        }
    }
    fn check_depth(&self, depth: usize) -> Result<()> {
        if depth > MAX_DEPTH {
            Err(self.err(format!("nodes nested deeper than {MAX_DEPTH} levels")))
        } else {
            Ok(())
        }
    }

    fn lookup_proto(&self, name: &str) -> Option<ProtoDef> {
        self.scopes
            .iter()
            .rev()
            .find_map(|s| s.protos.get(name).cloned())
    }
    fn lookup_def(&self, name: &str) -> Option<Rc<Node>> {
        self.scopes
            .iter()
            .rev()
            .find_map(|s| s.defs.get(name).cloned())
    }
    fn scope(&mut self) -> &mut Scope {
        if self.scopes.is_empty() {
            self.scopes.push(Scope::default());
        }
        let n = self.scopes.len() - 1;
        &mut self.scopes[n]
    }

    /// A statement at file or PROTO-body level: a node, PROTO, EXTERNPROTO or ROUTE.
    fn statement(&mut self, roots: &mut Vec<Rc<Node>>, depth: usize) -> Result<()> {
        match self.peek_id() {
            Some("PROTO") => self.proto(depth),
            Some("EXTERNPROTO") => self.externproto(),
            Some("ROUTE") => self.route(),
            Some(_) => {
                if let Some(n) = self.node_statement(depth)? {
                    roots.push(n);
                }
                Ok(())
            }
            None => Err(self.expected("a node, PROTO, EXTERNPROTO or ROUTE")),
        }
    }

    fn route(&mut self) -> Result<()> {
        self.pos += 1;
        self.id("the source 'node.event' of the ROUTE")?;
        if self.id("TO")? != "TO" {
            self.pos -= 1;
            return Err(self.expected("TO"));
        }
        self.id("the destination 'node.event' of the ROUTE")?;
        Ok(())
    }

    /// `DEF name node`, `USE name`, `NULL` or a node.
    fn node_statement(&mut self, depth: usize) -> Result<Option<Rc<Node>>> {
        self.check_depth(depth)?;
        let Some(word) = self.peek_id().map(str::to_string) else {
            return Err(self.expected("a node"));
        };
        match word.as_str() {
            "DEF" => {
                self.pos += 1;
                let name = self.id("a name after DEF")?;
                let node = self.node(depth + 1)?;
                self.scope().defs.insert(name, Rc::clone(&node));
                Ok(Some(node))
            }
            "USE" => {
                self.pos += 1;
                let line = self.line();
                let name = self.id("a name after USE")?;
                match self.lookup_def(&name) {
                    Some(n) => Ok(Some(n)),
                    None => Err(PgtError::at_line(
                        self.path,
                        line,
                        format!("USE of the undefined name '{name}' (expected a DEF of it earlier in the file)"),
                    )),
                }
            }
            "NULL" => {
                self.pos += 1;
                Ok(None)
            }
            _ => self.node(depth + 1).map(Some),
        }
    }

    /// `Type { fields }`.
    fn node(&mut self, depth: usize) -> Result<Rc<Node>> {
        self.check_depth(depth)?;
        let line = self.line();
        let type_name = self.id("a node type")?;
        let kind = match self.lookup_proto(&type_name) {
            Some(ProtoDef::Defined(p)) => NodeKind::Proto(p),
            Some(ProtoDef::Extern) => NodeKind::Extern,
            Some(ProtoDef::BeingDefined(at)) => {
                return Err(PgtError::at_line(
                    self.path,
                    line,
                    format!("the PROTO '{type_name}' (line {at}) instantiates itself"),
                ))
            }
            None if VRML97_NODES.contains(&type_name.as_str()) => NodeKind::Builtin,
            None => {
                return Err(PgtError::at_line(
                    self.path,
                    line,
                    format!("unknown node type '{type_name}': expected a VRML97 node or a PROTO declared before this line"),
                ))
            }
        };
        if self.peek().map(|t| &t.tok) != Some(&Tok::LBrace) {
            return Err(self.expected(&format!("'{{' after the node type '{type_name}'")));
        }
        self.pos += 1;
        let mut fields = Vec::new();
        loop {
            match self.peek().map(|t| &t.tok) {
                Some(Tok::RBrace) => {
                    self.pos += 1;
                    break;
                }
                None => {
                    return Err(PgtError::at_line(
                        self.path,
                        self.line(),
                        format!("unbalanced braces: expected '}}' to close the {type_name} node opened at line {line}, found the end of the file"),
                    ))
                }
                Some(Tok::Id(w)) => match w.as_str() {
                    "PROTO" => self.proto(depth)?,
                    "EXTERNPROTO" => self.externproto()?,
                    "ROUTE" => self.route()?,
                    "field" | "exposedField" | "eventIn" | "eventOut" => {
                        // Script interface declarations: `field SFNode x USE y`, `eventIn SFTime t`.
                        let kind = w.clone();
                        self.pos += 1;
                        self.id("a field type")?;
                        let name = self.id("a field name")?;
                        if self.peek_id() == Some("IS") {
                            self.pos += 1;
                            let target = self.id("a PROTO field name after IS")?;
                            fields.push((name, Value::Is(target)));
                        } else if kind == "field" || kind == "exposedField" {
                            let v = self.value(depth)?;
                            fields.push((name, v));
                        }
                    }
                    _ => {
                        let name = w.clone();
                        self.pos += 1;
                        if self.peek_id() == Some("IS") {
                            self.pos += 1;
                            let target = self.id("a PROTO field name after IS")?;
                            fields.push((name, Value::Is(target)));
                        } else {
                            let v = self.value(depth)?;
                            fields.push((name, v));
                        }
                    }
                },
                Some(_) => return Err(self.expected(&format!("a field name or '}}' in the {type_name} node"))),
            }
        }
        Ok(Rc::new(Node {
            type_name,
            kind,
            fields,
            line,
        }))
    }

    /// A field value (see the module documentation).
    fn value(&mut self, depth: usize) -> Result<Value> {
        self.check_depth(depth)?;
        match self.peek().map(|t| t.tok.clone()) {
            Some(Tok::Num(_)) => {
                let mut v = Vec::new();
                while let Some(Tok::Num(n)) = self.peek().map(|t| &t.tok) {
                    v.push(*n);
                    self.pos += 1;
                }
                Ok(Value::Nums(v))
            }
            Some(Tok::Str(s)) => {
                self.pos += 1;
                Ok(Value::Strs(vec![s]))
            }
            Some(Tok::Id(w)) if w == "TRUE" || w == "FALSE" => {
                self.pos += 1;
                Ok(Value::Bool(w == "TRUE"))
            }
            Some(Tok::Id(w)) => {
                let node_follows = matches!(w.as_str(), "DEF" | "USE" | "NULL")
                    || matches!(
                        self.toks.get(self.pos + 1).map(|t| &t.tok),
                        Some(Tok::LBrace)
                    );
                if !node_follows {
                    return Err(self.expected(
                        "a field value (numbers, a string, TRUE/FALSE, a node, NULL or [ … ])",
                    ));
                }
                Ok(Value::Node(self.node_statement(depth + 1)?))
            }
            Some(Tok::LBracket) => {
                let open = self.line();
                self.pos += 1;
                let (mut nums, mut strs, mut nodes) = (Vec::new(), Vec::new(), Vec::new());
                loop {
                    match self.peek().map(|t| t.tok.clone()) {
                        Some(Tok::RBracket) => {
                            self.pos += 1;
                            break;
                        }
                        None => {
                            return Err(PgtError::at_line(
                                self.path,
                                self.line(),
                                format!("unbalanced brackets: expected ']' to close the list opened at line {open}, found the end of the file"),
                            ))
                        }
                        Some(Tok::Num(n)) => {
                            nums.push(n);
                            self.pos += 1;
                        }
                        Some(Tok::Str(s)) => {
                            strs.push(s);
                            self.pos += 1;
                        }
                        Some(Tok::Id(w)) if w == "TRUE" || w == "FALSE" => {
                            nums.push(if w == "TRUE" { 1.0 } else { 0.0 });
                            self.pos += 1;
                        }
                        Some(Tok::Id(_)) => {
                            if let Some(n) = self.node_statement(depth + 1)? {
                                nodes.push(n);
                            }
                        }
                        Some(_) => return Err(self.expected(&format!("a value or ']' (list opened at line {open})"))),
                    }
                }
                let kinds = usize::from(!nums.is_empty())
                    + usize::from(!strs.is_empty())
                    + usize::from(!nodes.is_empty());
                if kinds > 1 {
                    return Err(PgtError::at_line(
                        self.path,
                        open,
                        "a list mixes numbers, strings and nodes",
                    ));
                }
                Ok(if !nodes.is_empty() {
                    Value::Nodes(nodes)
                } else if !strs.is_empty() {
                    Value::Strs(strs)
                } else if !nums.is_empty() {
                    Value::Nums(nums)
                } else {
                    Value::Empty
                })
            }
            _ => Err(self.expected("a field value")),
        }
    }

    /// `[ field|exposedField type name value | eventIn|eventOut type name … ]`; values only when
    /// `with_values` (PROTO, not EXTERNPROTO).
    fn interface(&mut self, with_values: bool, depth: usize) -> Result<Vec<(String, Value)>> {
        self.expect(Tok::LBracket, "'[' opening the interface")?;
        let mut fields = Vec::new();
        loop {
            match self.peek_id() {
                Some("field") | Some("exposedField") => {
                    self.pos += 1;
                    self.id("a field type")?;
                    let name = self.id("a field name")?;
                    let v = if with_values {
                        self.value(depth)?
                    } else {
                        Value::Empty
                    };
                    fields.push((name, v));
                }
                Some("eventIn") | Some("eventOut") => {
                    self.pos += 1;
                    self.id("an event type")?;
                    self.id("an event name")?;
                }
                _ => {
                    if self.peek().map(|t| &t.tok) == Some(&Tok::RBracket) {
                        self.pos += 1;
                        return Ok(fields);
                    }
                    return Err(self.expected(
                        "field, exposedField, eventIn, eventOut or ']' in the interface",
                    ));
                }
            }
        }
    }

    fn proto(&mut self, depth: usize) -> Result<()> {
        let line = self.line();
        self.pos += 1;
        let name = self.id("the PROTO's name")?;
        let fields = self.interface(true, depth + 1)?;
        let previous = self
            .scope()
            .protos
            .insert(name.clone(), ProtoDef::BeingDefined(line));
        self.expect(Tok::LBrace, "'{' opening the PROTO body")?;
        self.scopes.push(Scope::default());
        let mut body = Vec::new();
        let result = loop {
            match self.peek().map(|t| &t.tok) {
                Some(Tok::RBrace) => {
                    self.pos += 1;
                    break Ok(());
                }
                None => {
                    break Err(PgtError::at_line(
                        self.path,
                        self.line(),
                        format!("unbalanced braces: expected '}}' to close the body of the PROTO '{name}' opened at line {line}, found the end of the file"),
                    ))
                }
                _ => {
                    if let Err(e) = self.statement(&mut body, depth + 1) {
                        break Err(e);
                    }
                }
            }
        };
        self.scopes.pop();
        if let Err(e) = result {
            if let Some(p) = previous {
                self.scope().protos.insert(name, p);
            }
            return Err(e);
        }
        let proto = Rc::new(Proto {
            name: name.clone(),
            fields,
            body,
            line,
        });
        self.scope().protos.insert(name, ProtoDef::Defined(proto));
        Ok(())
    }

    fn externproto(&mut self) -> Result<()> {
        self.pos += 1;
        let name = self.id("the EXTERNPROTO's name")?;
        self.interface(false, 0)?;
        // The URL: a string or a list of strings.
        match self.value(0)? {
            Value::Strs(_) | Value::Empty => {}
            _ => return Err(self.expected("the EXTERNPROTO's URL (a string or a list of strings)")),
        }
        self.scope().protos.insert(name, ProtoDef::Extern);
        Ok(())
    }
}
