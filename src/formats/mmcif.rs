//! mmCIF (PDBx): the `_atom_site` category, as a `loop_` or as single key–value pairs.
//!
//! A CIF 1.1 tokenizer (whitespace-separated values, `'…'`/`"…"` quotes that close only before
//! whitespace, `;`-delimited text fields at the start of a line, `#` comments) feeds a reader
//! that needs `Cartn_x/y/z` and uses, where present: `type_symbol` (element), `auth_atom_id` /
//! `label_atom_id`, `label_alt_id`, `auth_comp_id` / `label_comp_id`, `auth_asym_id` /
//! `label_asym_id` (the chain, as PDB files name it), `auth_seq_id` / `label_seq_id`,
//! `pdbx_PDB_ins_code`, `occupancy`, `group_PDB`, `pdbx_PDB_model_num`. `.` and `?` mean missing.

use super::atoms::{atoms_to_particles, infer_element, Atom};
use super::elements::Element;
use super::file::text::finite_number;
use super::{Format, IncludeSpec, LoadedParticles};
use crate::error::{PgtError, Result};
use glam::DVec3;
use std::path::Path;

/// mmCIF in the table of formats ([`super::FORMATS`]).
pub const FORMAT: Format = Format {
    name: "mmcif",
    extensions: &["cif", "mmcif"],
    description: "mmCIF / PDBx",
    particles: "_atom_site rows",
    read: Some(read),
    details: Some(details),
    frames: Some(open_frames),
    topology: Some(read_atoms),
    ..Format::NOTHING
};

/// The [`super::OpenFrames`] of mmCIF: one frame per `pdbx_PDB_model_num`, in order of first
/// appearance. The `_atom_site` loop is tokenised as a whole (CIF has no per-model index and a
/// row's values may span lines), so the file is parsed once at open and the atoms are kept
/// grouped by model: fine for NMR ensembles; MD trajectories belong in DCD or XTC.
pub fn open_frames(
    spec: &IncludeSpec,
    source: super::file::ByteSource,
) -> Result<Box<dyn super::frame_source::FrameSource>> {
    let bytes = source.read_all("the file")?;
    let (atoms, warnings) = read_atoms(source.path(), &bytes)?;
    let mut models: Vec<(i64, Vec<Atom>)> = Vec::new();
    for a in atoms {
        match models.iter_mut().find(|(m, _)| *m == a.model) {
            Some((_, group)) => group.push(a),
            None => models.push((a.model, vec![a])),
        }
    }
    if models.is_empty() {
        return Err(PgtError::in_file(
            source.path(),
            format!(
                "the file holds no particles: no _atom_site rows ({})",
                warnings.join("; ")
            ),
        ));
    }
    Ok(Box::new(CifFrames {
        spec: spec.clone(),
        path: source.path().to_path_buf(),
        models,
    }))
}

/// The models of an mmCIF file as frames ([`open_frames`]).
struct CifFrames {
    spec: IncludeSpec,
    path: std::path::PathBuf,
    models: Vec<(i64, Vec<Atom>)>,
}

impl super::frame_source::FrameSource for CifFrames {
    fn path(&self) -> &Path {
        &self.path
    }
    fn info(&self) -> super::frame_source::FrameInfo {
        let sizes: Vec<usize> = self.models.iter().map(|(_, a)| a.len()).collect();
        super::frame_source::FrameInfo {
            count: self.models.len(),
            atoms_per_frame: sizes
                .first()
                .copied()
                .filter(|&n| sizes.iter().all(|&m| m == n)),
            time_step_ps: None,
        }
    }
    fn read_frame(&self, index: usize) -> Result<super::frame_source::Frame> {
        let (_, atoms) = self.models.get(index).ok_or_else(|| {
            super::frame_source::past_the_end(&self.path, index, self.models.len())
        })?;
        let mut spec = self.spec.clone();
        spec.path = self.path.clone();
        spec.model = None;
        let loaded = atoms_to_particles(&spec, atoms.clone(), Vec::new())?;
        let particles = super::frame_source::finish_frame(&spec, &self.path, index, loaded)?;
        Ok(super::frame_source::Frame {
            index,
            time_ps: None,
            particles,
        })
    }
}

/// The [`super::Reader`] of mmCIF: every `_atom_site` row, then the include's selections
/// ([`atoms_to_particles`]).
pub fn read(spec: &IncludeSpec, bytes: &[u8]) -> Result<LoadedParticles> {
    let (atoms, warnings) = read_atoms(&spec.path, bytes)?;
    atoms_to_particles(spec, atoms, warnings)
}

/// The [`super::Details`] of mmCIF: models and chains ([`super::atoms::details`]).
fn details(path: &Path, bytes: &[u8]) -> Result<serde_json::Map<String, serde_json::Value>> {
    Ok(super::atoms::details(&read_atoms(path, bytes)?.0))
}

#[derive(Debug, Clone, PartialEq)]
enum Tok<'a> {
    /// A bare word (also `loop_`, `data_x`, tags).
    Word(&'a str),
    /// A quoted string or text field (never a reserved word; `.`/`?` inside quotes are values).
    Quoted(String),
}

struct Token<'a> {
    tok: Tok<'a>,
    line: usize,
}

fn tokenize<'a>(path: &Path, text: &'a str) -> Result<Vec<Token<'a>>> {
    let mut out = Vec::new();
    let bytes = text.as_bytes();
    let mut i = 0usize;
    let mut line = 1usize;
    let mut at_line_start = true;
    while i < bytes.len() {
        let c = bytes.get(i).copied().unwrap_or(b' ');
        if c == b'\n' {
            line += 1;
            i += 1;
            at_line_start = true;
            continue;
        }
        if c.is_ascii_whitespace() {
            i += 1;
            at_line_start = false;
            continue;
        }
        if c == b'#' {
            while i < bytes.len() && bytes.get(i) != Some(&b'\n') {
                i += 1;
            }
            continue;
        }
        if c == b';' && at_line_start {
            // Text field: up to a line that starts with ';'.
            let start_line = line;
            let start = i + 1;
            let mut j = start;
            loop {
                match bytes.get(j) {
                    None => {
                        return Err(PgtError::at_line(
                            path,
                            start_line,
                            "unterminated text field: expected a line starting with ';'",
                        ))
                    }
                    Some(b'\n') => {
                        line += 1;
                        if bytes.get(j + 1) == Some(&b';') {
                            let body = text.get(start..j).unwrap_or_default().to_string();
                            out.push(Token {
                                tok: Tok::Quoted(body),
                                line: start_line,
                            });
                            i = j + 2;
                            break;
                        }
                    }
                    Some(_) => {}
                }
                j += 1;
            }
            at_line_start = false;
            continue;
        }
        at_line_start = false;
        if c == b'\'' || c == b'"' {
            let start = i + 1;
            let mut j = start;
            loop {
                match bytes.get(j) {
                    None | Some(b'\n') => {
                        return Err(PgtError::at_line(
                            path,
                            line,
                            format!(
                                "unterminated quoted string: expected a closing {}",
                                c as char
                            ),
                        ))
                    }
                    Some(&q)
                        if q == c && bytes.get(j + 1).is_none_or(|n| n.is_ascii_whitespace()) =>
                    {
                        break
                    }
                    Some(_) => j += 1,
                }
            }
            out.push(Token {
                tok: Tok::Quoted(text.get(start..j).unwrap_or_default().to_string()),
                line,
            });
            i = j + 1;
            continue;
        }
        let start = i;
        // `c` is not whitespace here, so every word is at least one byte long.
        i += 1;
        while i < bytes.len() && !bytes.get(i).is_some_and(|b| b.is_ascii_whitespace()) {
            i += 1;
        }
        out.push(Token {
            tok: Tok::Word(text.get(start..i).unwrap_or_default()),
            line,
        });
    }
    Ok(out)
}

fn is_reserved(w: &str) -> bool {
    let l = w.to_ascii_lowercase();
    l == "loop_"
        || l.starts_with("data_")
        || l.starts_with("save_")
        || l == "global_"
        || l == "stop_"
}

/// A value with its line; `None` for `.` and `?`.
type Value = (Option<String>, usize);

fn value_of(t: &Token) -> Value {
    match &t.tok {
        Tok::Word(w) if *w == "." || *w == "?" => (None, t.line),
        Tok::Word(w) => (Some((*w).to_string()), t.line),
        Tok::Quoted(s) => (Some(s.clone()), t.line),
    }
}

/// The `_atom_site` table: column names (without the prefix, lower case) and rows.
fn atom_site_table(path: &Path, toks: &[Token]) -> Result<(Vec<String>, Vec<Vec<Value>>)> {
    const PREFIX: &str = "_atom_site.";
    let is_atom_tag = |t: &Token| matches!(t.tok, Tok::Word(w) if w.len() > PREFIX.len() && w.get(..PREFIX.len()).is_some_and(|p| p.eq_ignore_ascii_case(PREFIX)));
    let mut i = 0;
    while i < toks.len() {
        let is_loop = matches!(toks.get(i).map(|t| &t.tok), Some(Tok::Word(w)) if w.eq_ignore_ascii_case("loop_"));
        if is_loop && toks.get(i + 1).is_some_and(is_atom_tag) {
            let loop_line = toks.get(i).map_or(1, |t| t.line);
            let mut names = Vec::new();
            let mut j = i + 1;
            while let Some(t) = toks.get(j).filter(|t| is_atom_tag(t)) {
                if let Tok::Word(w) = t.tok {
                    names.push(
                        w.get(PREFIX.len()..)
                            .unwrap_or_default()
                            .to_ascii_lowercase(),
                    );
                }
                j += 1;
            }
            let mut values = Vec::new();
            while let Some(t) = toks.get(j) {
                match &t.tok {
                    Tok::Word(w) if w.starts_with('_') || is_reserved(w) => break,
                    _ => values.push(value_of(t)),
                }
                j += 1;
            }
            if values.len() % names.len().max(1) != 0 {
                let last = values.last().map_or(loop_line, |v| v.1);
                return Err(PgtError::at_line(
                    path,
                    last,
                    format!(
                        "the _atom_site loop has {} values, not a multiple of its {} columns (a row is incomplete)",
                        values.len(),
                        names.len()
                    ),
                ));
            }
            let rows = values
                .chunks(names.len().max(1))
                .map(<[Value]>::to_vec)
                .collect();
            return Ok((names, rows));
        }
        i += 1;
    }
    // Single atom written as key–value pairs.
    let mut names = Vec::new();
    let mut row = Vec::new();
    let mut k = 0;
    while k < toks.len() {
        if let Some(t) = toks.get(k).filter(|t| is_atom_tag(t)) {
            if let Tok::Word(w) = t.tok {
                let v = toks.get(k + 1).ok_or_else(|| {
                    PgtError::at_line(
                        path,
                        t.line,
                        format!("expected a value after {w}, found the end of the file"),
                    )
                })?;
                names.push(
                    w.get(PREFIX.len()..)
                        .unwrap_or_default()
                        .to_ascii_lowercase(),
                );
                row.push(value_of(v));
                k += 1;
            }
        }
        k += 1;
    }
    let rows = if row.is_empty() {
        Vec::new()
    } else {
        vec![row]
    };
    Ok((names, rows))
}

/// Reads every atom of every model of an mmCIF file's text.
pub fn read_atoms(path: &Path, bytes: &[u8]) -> Result<(Vec<Atom>, Vec<String>)> {
    let text = String::from_utf8_lossy(bytes);
    let toks = tokenize(path, &text)?;
    let (names, rows) = atom_site_table(path, &toks)?;
    let mut warnings = Vec::new();
    if rows.is_empty() {
        warnings.push(format!("{}: no _atom_site records", path.display()));
        return Ok((Vec::new(), warnings));
    }
    let col = |n: &str| names.iter().position(|c| c == n);
    let first = |ns: &[&str]| ns.iter().find_map(|n| col(n));
    let need = |n: &str| {
        col(n).ok_or_else(|| {
            PgtError::in_file(
                path,
                format!("the _atom_site table has no _atom_site.{n} column"),
            )
        })
    };
    let (cx, cy, cz) = (need("cartn_x")?, need("cartn_y")?, need("cartn_z")?);
    let c_elem = col("type_symbol");
    let c_name = first(&["auth_atom_id", "label_atom_id"]);
    let c_alt = col("label_alt_id");
    let c_res = first(&["auth_comp_id", "label_comp_id"]);
    let c_chain = first(&["auth_asym_id", "label_asym_id"]);
    let c_seq = first(&["auth_seq_id", "label_seq_id"]);
    let c_ins = col("pdbx_pdb_ins_code");
    let c_occ = col("occupancy");
    let c_group = col("group_pdb");
    let c_model = col("pdbx_pdb_model_num");

    let mut atoms = Vec::with_capacity(rows.len());
    for row in &rows {
        let get = |c: Option<usize>| c.and_then(|c| row.get(c)).and_then(|v| v.0.clone());
        let line = row.first().map_or(1, |v| v.1);
        let number = |c: usize, what: &str| -> Result<f64> {
            let (v, l) = row.get(c).cloned().unwrap_or((None, line));
            let s = v.ok_or_else(|| {
                PgtError::at_line(
                    path,
                    l,
                    format!("expected a number for {what}, found '.' or '?'"),
                )
            })?;
            finite_number(&s, what).map_err(|m| PgtError::at_line(path, l, m))
        };
        let position = DVec3::new(
            number(cx, "_atom_site.Cartn_x")?,
            number(cy, "_atom_site.Cartn_y")?,
            number(cz, "_atom_site.Cartn_z")?,
        );
        let occupancy = match c_occ {
            Some(c) if get(Some(c)).is_some() => number(c, "_atom_site.occupancy")?,
            _ => 1.0,
        };
        let hetatm = get(c_group).is_some_and(|g| g.eq_ignore_ascii_case("HETATM"));
        let name = get(c_name).unwrap_or_default();
        let element = get(c_elem)
            .and_then(|e| Element::from_symbol(&e))
            .or_else(|| infer_element(&format!("{name:<4}"), hetatm));
        let model = match get(c_model) {
            Some(m) => m.parse::<i64>().map_err(|_| {
                PgtError::at_line(
                    path,
                    line,
                    format!("expected an integer for _atom_site.pdbx_PDB_model_num, found '{m}'"),
                )
            })?,
            None => 1,
        };
        atoms.push(Atom {
            position,
            element,
            name,
            alt_loc: get(c_alt),
            occupancy,
            residue_name: get(c_res).unwrap_or_default(),
            chain: get(c_chain).unwrap_or_default(),
            residue: format!(
                "{}{}",
                get(c_seq).unwrap_or_default(),
                get(c_ins).unwrap_or_default()
            ),
            model,
            line,
        });
    }
    Ok((atoms, warnings))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokenizes_quotes_and_text_fields() {
        let text = "data_x\n_a 'it''s' \n;line1\nline2\n;\n_b \"q\" # c\n";
        let toks = tokenize(Path::new("t.cif"), text).expect("ok");
        let v: Vec<Tok> = toks.into_iter().map(|t| t.tok).collect();
        assert_eq!(v.get(2), Some(&Tok::Quoted("it''s".into())));
        assert_eq!(v.get(3), Some(&Tok::Quoted("line1\nline2".into())));
        assert_eq!(v.get(5), Some(&Tok::Quoted("q".into())));
        assert_eq!(v.len(), 6);
    }

    #[test]
    fn incomplete_row_is_an_error() {
        let text = "data_x\nloop_\n_atom_site.Cartn_x\n_atom_site.Cartn_y\n_atom_site.Cartn_z\n1 2 3\n4 5\n";
        let e = read_atoms(Path::new("t.cif"), text.as_bytes())
            .expect_err("bad")
            .to_string();
        assert!(e.contains("t.cif:7") && e.contains("multiple"), "{e}");
    }

    #[test]
    fn form_feed_is_whitespace() {
        // Found by the mutation smoke test: a form feed once produced empty words forever.
        let toks = tokenize(Path::new("t.cif"), "a\x0cb\x0b c").expect("ok");
        assert_eq!(toks.len(), 3);
    }

    #[test]
    fn unterminated_text_field() {
        let e = read_atoms(Path::new("t.cif"), b"data_x\n;abc\n")
            .expect_err("bad")
            .to_string();
        assert!(e.contains("t.cif:2"), "{e}");
    }
}
