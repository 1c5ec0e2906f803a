//! Evaluation of a VRML97 node tree into spheres: transforms composed down the tree, PROTO
//! instances expanded with their `IS` bindings, shapes turned into particles.
//!
//! * `Transform`: M = T·C·R·SR·S·SR⁻¹·C⁻¹ (ISO/IEC 14772-1 §6.52), composed parent × child.
//! * `Group`, `Anchor`, `Collision` (its `proxy` is not drawn), `Billboard` (its view-dependent
//!   rotation is not applied): their `children`. `Switch`: `choice[whichChoice]` (nothing for −1
//!   or out of range). `LOD`: `level[0]`, the most detailed. `Inline`: not loaded (a warning).
//! * `Shape` with `Sphere` (radius 1 by default): a particle at M·0. Under a transform that is not
//!   a similarity (a non-uniform scale), the ellipsoid becomes the sphere of the same volume,
//!   radius r·∛|det M₃ₓ₃|, with one warning that counts them; under a similarity that is exactly
//!   the scaled radius.
//! * `Shape` with an `IndexedFaceSet` whose vertices (at least 12) all lie at one distance from
//!   their centroid (within 0.5 %) — Jmol writes each atom as a `USE` of one unit geodesic sphere
//!   under `Transform { scale r r r }` — becomes a sphere through those vertices, with a warning
//!   that counts them. Other geometry is skipped with one warning that counts it by type.
//! * Colour: `Material.diffuseColor` (VRML default 0.8 0.8 0.8), or `emissiveColor` where the
//!   diffuse colour is black and the emissive one is not; VRML colours are sRGB display values and
//!   are decoded to linear RGB. Opacity: 1 − `transparency`, only where the file writes a
//!   `transparency` (otherwise the scene's default opacity applies). No `Appearance` or a `NULL`
//!   material (VRML's unlit white) leaves the colour to the scene's default.

use super::parser::{Node, NodeKind, Proto, Value};
use crate::color::srgb_to_linear;
use crate::error::{Location, PgtError, Result};
use crate::formats::ParticleRecord;
use glam::{DMat3, DMat4, DQuat, DVec3};
use std::collections::{BTreeMap, HashMap};
use std::path::Path;
use std::rc::Rc;

/// Deepest evaluation (nested nodes plus PROTO expansions).
const MAX_EVAL_DEPTH: usize = 512;
/// Most node visits one file may cause (DEF/USE can multiply a small file into a huge scene).
const MAX_VISITS: u64 = 20_000_000;
/// Most spheres one file may produce (≈ 100 bytes each): DEF/USE can make a few hundred bytes
/// of text stand for billions of spheres, and pgt refuses rather than allocating for them.
pub const MAX_SPHERES: usize = 4_000_000;
/// Relative spread of vertex distances below which a mesh counts as a sphere.
const MESH_SPHERE_TOLERANCE: f64 = 5e-3;
/// Fewest vertices of a mesh recognised as a sphere.
const MESH_SPHERE_MIN_VERTICES: usize = 12;

/// The `IS` bindings of one PROTO instance: field name → (value, the bindings it is read in).
struct Env {
    bindings: HashMap<String, (Value, Option<Rc<Env>>)>,
}

type EnvRef = Option<Rc<Env>>;

/// What evaluation produced.
pub struct Evaluated {
    /// The spheres, in traversal order.
    pub records: Vec<ParticleRecord>,
    /// Summary warnings (skipped shapes, recognised meshes, …).
    pub warnings: Vec<String>,
}

struct Ctx<'a> {
    path: &'a Path,
    records: Vec<ParticleRecord>,
    skipped: BTreeMap<String, usize>,
    non_uniform: usize,
    mesh_spheres: usize,
    externs: usize,
    inlines: usize,
    billboards: usize,
    visits: u64,
}

/// Evaluates the root nodes of a file.
pub fn evaluate(path: &Path, roots: &[Rc<Node>]) -> Result<Evaluated> {
    let mut ctx = Ctx {
        path,
        records: Vec::new(),
        skipped: BTreeMap::new(),
        non_uniform: 0,
        mesh_spheres: 0,
        externs: 0,
        inlines: 0,
        billboards: 0,
        visits: 0,
    };
    for r in roots {
        ctx.walk(r, &None, DMat4::IDENTITY, 0)?;
    }
    let mut warnings = Vec::new();
    let p = path.display();
    if !ctx.skipped.is_empty() {
        let total: usize = ctx.skipped.values().sum();
        let list: Vec<String> = ctx
            .skipped
            .iter()
            .map(|(k, v)| format!("{v} {k}"))
            .collect();
        warnings.push(format!(
            "{p}: skipped {total} non-sphere shapes ({})",
            list.join(", ")
        ));
    }
    if ctx.mesh_spheres > 0 {
        warnings.push(format!(
            "{p}: {} IndexedFaceSet meshes have all vertices at one distance from their centroid; drawn as spheres through their vertices",
            ctx.mesh_spheres
        ));
    }
    if ctx.non_uniform > 0 {
        warnings.push(format!(
            "{p}: {} spheres are under a non-uniform scale; each is drawn as the sphere of the same volume",
            ctx.non_uniform
        ));
    }
    if ctx.externs > 0 {
        warnings.push(format!(
            "{p}: {} EXTERNPROTO instances were not loaded",
            ctx.externs
        ));
    }
    if ctx.inlines > 0 {
        warnings.push(format!("{p}: {} Inline nodes were not loaded", ctx.inlines));
    }
    if ctx.billboards > 0 {
        warnings.push(format!(
            "{p}: {} Billboard nodes drawn without their view-dependent rotation",
            ctx.billboards
        ));
    }
    Ok(Evaluated {
        records: ctx.records,
        warnings,
    })
}

impl Ctx<'_> {
    fn err(&self, line: usize, msg: impl Into<String>) -> PgtError {
        PgtError::at_line(self.path, line, msg)
    }

    /// A field of `node` read in `env`, following `IS` to the instance's value.
    fn field(&self, node: &Node, env: &EnvRef, name: &str) -> Result<Option<(Value, EnvRef)>> {
        let Some(v) = node.field(name) else {
            return Ok(None);
        };
        let mut v = v.clone();
        let mut env = env.clone();
        let mut hops = 0;
        while let Value::Is(target) = &v {
            hops += 1;
            let bound = env.as_ref().and_then(|e| e.bindings.get(target).cloned());
            match bound {
                Some((bv, be)) if hops <= MAX_EVAL_DEPTH => {
                    v = bv;
                    env = be;
                }
                _ => {
                    return Err(self.err(
                        node.line,
                        format!(
                        "'{name} IS {target}': '{target}' is not a field of the enclosing PROTO"
                    ),
                    ))
                }
            }
        }
        Ok(Some((v, env)))
    }

    fn nums(&self, node: &Node, env: &EnvRef, name: &str, want: usize) -> Result<Option<Vec<f64>>> {
        match self.field(node, env, name)? {
            None => Ok(None),
            Some((Value::Nums(v), _)) if v.len() == want || want == 0 => Ok(Some(v)),
            Some((other, _)) => Err(self.err(
                node.line,
                format!(
                    "{}.{name}: expected {} number{}, found {}",
                    node.type_name,
                    want,
                    if want == 1 { "" } else { "s" },
                    describe(&other)
                ),
            )),
        }
    }

    fn vec3(&self, node: &Node, env: &EnvRef, name: &str, default: DVec3) -> Result<DVec3> {
        Ok(self
            .nums(node, env, name, 3)?
            .map_or(default, |v| DVec3::new(v[0], v[1], v[2])))
    }

    fn rotation(&self, node: &Node, env: &EnvRef, name: &str) -> Result<DQuat> {
        Ok(match self.nums(node, env, name, 4)? {
            Some(v) => {
                let axis = DVec3::new(v[0], v[1], v[2]);
                let len = axis.length();
                if len > 0.0 && len.is_finite() && v[3].is_finite() {
                    DQuat::from_axis_angle(axis / len, v[3])
                } else {
                    DQuat::IDENTITY
                }
            }
            None => DQuat::IDENTITY,
        })
    }

    /// A node-valued field: (node, env) pairs (an SFNode gives zero or one).
    fn nodes(&self, node: &Node, env: &EnvRef, name: &str) -> Result<Vec<(Rc<Node>, EnvRef)>> {
        match self.field(node, env, name)? {
            None | Some((Value::Empty, _)) | Some((Value::Node(None), _)) => Ok(Vec::new()),
            Some((Value::Node(Some(n)), e)) => Ok(vec![(n, e)]),
            Some((Value::Nodes(v), e)) => Ok(v.into_iter().map(|n| (n, e.clone())).collect()),
            Some((other, _)) => Err(self.err(
                node.line,
                format!(
                    "{}.{name}: expected nodes, found {}",
                    node.type_name,
                    describe(&other)
                ),
            )),
        }
    }

    /// Expands PROTO instances down to a built-in node. `None`: an empty PROTO body or an
    /// EXTERNPROTO instance.
    fn resolve(&mut self, node: &Rc<Node>, env: &EnvRef) -> Result<Option<(Rc<Node>, EnvRef)>> {
        let mut node = Rc::clone(node);
        let mut env = env.clone();
        for _ in 0..MAX_EVAL_DEPTH {
            let proto: Rc<Proto> = match &node.kind {
                NodeKind::Builtin => return Ok(Some((node, env))),
                NodeKind::Extern => {
                    self.externs += 1;
                    return Ok(None);
                }
                NodeKind::Proto(p) => Rc::clone(p),
            };
            let mut bindings = HashMap::new();
            for (name, default) in &proto.fields {
                bindings.insert(name.clone(), (default.clone(), None));
            }
            for (name, v) in &node.fields {
                if !bindings.contains_key(name) {
                    return Err(self.err(
                        node.line,
                        format!(
                            "the PROTO '{}' (line {}) has no field '{name}'",
                            proto.name, proto.line
                        ),
                    ));
                }
                // An instance's own `IS` (inside another PROTO body) is read in the outer env.
                let resolved = match v {
                    Value::Is(_) => self
                        .field(&node, &env, name)?
                        .unwrap_or((Value::Empty, None)),
                    other => (other.clone(), env.clone()),
                };
                bindings.insert(name.clone(), resolved);
            }
            let Some(first) = proto.body.first() else {
                return Ok(None);
            };
            env = Some(Rc::new(Env { bindings }));
            node = Rc::clone(first);
        }
        Err(self.err(node.line, "PROTO expansion deeper than the limit"))
    }

    fn walk(&mut self, node: &Rc<Node>, env: &EnvRef, m: DMat4, depth: usize) -> Result<()> {
        self.visits += 1;
        if self.visits > MAX_VISITS {
            return Err(self.err(
                node.line,
                format!("the scene expands to more than {MAX_VISITS} nodes (DEF/USE)"),
            ));
        }
        if depth > MAX_EVAL_DEPTH {
            return Err(self.err(
                node.line,
                format!("nodes nested deeper than {MAX_EVAL_DEPTH} levels"),
            ));
        }
        let Some((node, env)) = self.resolve(node, env)? else {
            return Ok(());
        };
        match node.type_name.as_str() {
            "Transform" => {
                let t = self.vec3(&node, &env, "translation", DVec3::ZERO)?;
                let c = self.vec3(&node, &env, "center", DVec3::ZERO)?;
                let r = self.rotation(&node, &env, "rotation")?;
                let s = self.vec3(&node, &env, "scale", DVec3::ONE)?;
                let sr = self.rotation(&node, &env, "scaleOrientation")?;
                let local = DMat4::from_translation(t + c)
                    * DMat4::from_quat(r)
                    * DMat4::from_quat(sr)
                    * DMat4::from_scale(s)
                    * DMat4::from_quat(sr.inverse())
                    * DMat4::from_translation(-c);
                for (child, e) in self.nodes(&node, &env, "children")? {
                    self.walk(&child, &e, m * local, depth + 1)?;
                }
            }
            "Group" | "Anchor" | "Collision" | "Billboard" => {
                if node.type_name == "Billboard" {
                    self.billboards += 1;
                }
                for (child, e) in self.nodes(&node, &env, "children")? {
                    self.walk(&child, &e, m, depth + 1)?;
                }
            }
            "Switch" => {
                let which = self
                    .nums(&node, &env, "whichChoice", 1)?
                    .map_or(-1.0, |v| v[0]);
                let choices = self.nodes(&node, &env, "choice")?;
                if which >= 0.0 {
                    if let Some((child, e)) = choices.get(which as usize) {
                        self.walk(child, e, m, depth + 1)?;
                    }
                }
            }
            "LOD" => {
                if let Some((child, e)) = self.nodes(&node, &env, "level")?.first() {
                    self.walk(child, e, m, depth + 1)?;
                }
            }
            "Inline" => self.inlines += 1,
            "Shape" => self.shape(&node, &env, m)?,
            _ => {}
        }
        Ok(())
    }

    fn shape(&mut self, node: &Rc<Node>, env: &EnvRef, m: DMat4) -> Result<()> {
        let Some((geom, genv)) = self.nodes(node, env, "geometry")?.into_iter().next() else {
            return Ok(());
        };
        let Some((geom, genv)) = self.resolve(&geom, &genv)? else {
            return Ok(());
        };
        let (center, radius) = match geom.type_name.as_str() {
            "Sphere" => {
                let r = self.nums(&geom, &genv, "radius", 1)?.map_or(1.0, |v| v[0]);
                (DVec3::ZERO, r)
            }
            "IndexedFaceSet" => match self.mesh_sphere(&geom, &genv)? {
                Some(cr) => {
                    self.mesh_spheres += 1;
                    cr
                }
                None => {
                    *self.skipped.entry(geom.type_name.clone()).or_insert(0) += 1;
                    return Ok(());
                }
            },
            other => {
                *self.skipped.entry(other.to_string()).or_insert(0) += 1;
                return Ok(());
            }
        };
        let lin = DMat3::from_mat4(m);
        let (c0, c1, c2) = (lin.x_axis, lin.y_axis, lin.z_axis);
        let l2 = [
            c0.length_squared(),
            c1.length_squared(),
            c2.length_squared(),
        ];
        let mean = (l2[0] + l2[1] + l2[2]) / 3.0;
        let off = c0.dot(c1).abs().max(c0.dot(c2).abs()).max(c1.dot(c2).abs());
        let spread = l2.iter().map(|v| (v - mean).abs()).fold(off, f64::max);
        if spread > 1e-9 * mean.max(f64::MIN_POSITIVE) {
            self.non_uniform += 1;
        }
        let scale = lin.determinant().abs().cbrt();
        let (color, opacity) = self.appearance(node, env)?;
        let (center, radius) = (m.transform_point3(center), radius * scale);
        if !center.is_finite() || !radius.is_finite() {
            return Err(self.err(geom.line, "the sphere's position or radius is not finite"));
        }
        if self.records.len() >= MAX_SPHERES {
            return Err(self.err(
                geom.line,
                format!("the scene expands to more than {MAX_SPHERES} spheres; pgt reads at most that many from a VRML file"),
            ));
        }
        self.records.push(ParticleRecord {
            ellipsoid: None,
            center,
            radius,
            color,
            opacity,
            sigma: None,
            location: Location::Line(geom.line),
        });
        Ok(())
    }

    /// The centre and radius of a mesh whose vertices all lie on one sphere.
    fn mesh_sphere(&self, geom: &Node, env: &EnvRef) -> Result<Option<(DVec3, f64)>> {
        let Some((coord, cenv)) = self.nodes(geom, env, "coord")?.into_iter().next() else {
            return Ok(None);
        };
        if !matches!(coord.kind, NodeKind::Builtin) || coord.type_name != "Coordinate" {
            return Ok(None);
        }
        let Some(p) = self.nums(&coord, &cenv, "point", 0)? else {
            return Ok(None);
        };
        if p.len() % 3 != 0 || p.len() / 3 < MESH_SPHERE_MIN_VERTICES {
            return Ok(None);
        }
        let pts: Vec<DVec3> = p
            .chunks_exact(3)
            .map(|c| DVec3::new(c[0], c[1], c[2]))
            .collect();
        let centroid = pts.iter().copied().sum::<DVec3>() / pts.len() as f64;
        let d: Vec<f64> = pts.iter().map(|q| (*q - centroid).length()).collect();
        let mean = d.iter().sum::<f64>() / d.len() as f64;
        if !(mean > 0.0 && mean.is_finite()) {
            return Ok(None);
        }
        let ok = d
            .iter()
            .all(|x| (x - mean).abs() <= MESH_SPHERE_TOLERANCE * mean);
        Ok(ok.then_some((centroid, mean)))
    }

    fn appearance(&mut self, shape: &Node, env: &EnvRef) -> Result<(Option<DVec3>, Option<f64>)> {
        let Some((app, aenv)) = self.nodes(shape, env, "appearance")?.into_iter().next() else {
            return Ok((None, None));
        };
        let Some((app, aenv)) = self.resolve(&app, &aenv)? else {
            return Ok((None, None));
        };
        let Some((mat, menv)) = self.nodes(&app, &aenv, "material")?.into_iter().next() else {
            return Ok((None, None));
        };
        let Some((mat, menv)) = self.resolve(&mat, &menv)? else {
            return Ok((None, None));
        };
        if mat.type_name != "Material" {
            return Ok((None, None));
        }
        let diffuse = self.vec3(&mat, &menv, "diffuseColor", DVec3::splat(0.8))?;
        let emissive = self.vec3(&mat, &menv, "emissiveColor", DVec3::ZERO)?;
        let display = if diffuse == DVec3::ZERO && emissive != DVec3::ZERO {
            emissive
        } else {
            diffuse
        };
        let color = DVec3::new(
            srgb_to_linear(display.x.max(0.0)),
            srgb_to_linear(display.y.max(0.0)),
            srgb_to_linear(display.z.max(0.0)),
        );
        let opacity = self
            .nums(&mat, &menv, "transparency", 1)?
            .map(|t| 1.0 - t[0]);
        Ok((Some(color), opacity))
    }
}

fn describe(v: &Value) -> String {
    match v {
        Value::Nums(n) => format!("{} number(s)", n.len()),
        Value::Bool(_) => "a boolean".into(),
        Value::Strs(_) => "a string".into(),
        Value::Node(None) => "NULL".into(),
        Value::Node(Some(n)) => format!("a {} node", n.type_name),
        Value::Nodes(_) => "a list of nodes".into(),
        Value::Is(t) => format!("IS {t}"),
        Value::Empty => "[]".into(),
    }
}
