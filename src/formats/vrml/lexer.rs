//! VRML97 tokens (ISO/IEC 14772-1 §5.1): `{ } [ ]`, strings, numbers, identifiers; commas are
//! whitespace, `#` starts a comment to the end of the line (outside strings).

use crate::error::{PgtError, Result};
use std::path::Path;

/// A token's kind.
#[derive(Debug, Clone, PartialEq)]
pub enum Tok {
    /// `{`
    LBrace,
    /// `}`
    RBrace,
    /// `[`
    LBracket,
    /// `]`
    RBracket,
    /// A number (integers, floats, `0x` hexadecimal).
    Num(f64),
    /// A quoted string with `\"` and `\\` unescaped.
    Str(String),
    /// An identifier or keyword (`DEF`, `Transform`, `TRUE`, `ROUTE`, `a.b`).
    Id(String),
}

/// A token and the 1-based line it starts on.
#[derive(Debug, Clone, PartialEq)]
pub struct Token {
    /// The token.
    pub tok: Tok,
    /// 1-based line where it starts.
    pub line: usize,
}

/// Largest number of tokens pgt accepts (a guard against absurd inputs; 4 GiB of text is
/// at most ~2·10⁹ tokens, real files are far below this).
const MAX_TOKENS: usize = 1 << 31;

fn is_delimiter(c: u8) -> bool {
    c.is_ascii_whitespace() || matches!(c, b',' | b'{' | b'}' | b'[' | b']' | b'"' | b'#')
}

/// Splits VRML text into tokens. The header line (`#VRML V2.0 utf8 …`) is a comment like any other.
pub fn tokenize(path: &Path, text: &[u8]) -> Result<Vec<Token>> {
    let mut out = Vec::new();
    let mut i = 0usize;
    let mut line = 1usize;
    while let Some(&c) = text.get(i) {
        match c {
            b'\n' => {
                line += 1;
                i += 1;
            }
            b'#' => {
                while text.get(i).is_some_and(|&c| c != b'\n') {
                    i += 1;
                }
            }
            _ if c.is_ascii_whitespace() || c == b',' => i += 1,
            b'{' | b'}' | b'[' | b']' => {
                let tok = match c {
                    b'{' => Tok::LBrace,
                    b'}' => Tok::RBrace,
                    b'[' => Tok::LBracket,
                    _ => Tok::RBracket,
                };
                out.push(Token { tok, line });
                i += 1;
            }
            b'"' => {
                let start_line = line;
                let mut s = Vec::new();
                i += 1;
                loop {
                    match text.get(i) {
                        None => {
                            return Err(PgtError::at_line(
                                path,
                                start_line,
                                "unterminated string: expected a closing '\"'",
                            ))
                        }
                        Some(b'"') => {
                            i += 1;
                            break;
                        }
                        Some(b'\\') => {
                            if let Some(&n) = text.get(i + 1) {
                                s.push(n);
                                if n == b'\n' {
                                    line += 1;
                                }
                            }
                            i += 2;
                        }
                        Some(&b) => {
                            if b == b'\n' {
                                line += 1;
                            }
                            s.push(b);
                            i += 1;
                        }
                    }
                }
                out.push(Token {
                    tok: Tok::Str(String::from_utf8_lossy(&s).into_owned()),
                    line: start_line,
                });
            }
            _ => {
                let start = i;
                while text.get(i).is_some_and(|&c| !is_delimiter(c)) {
                    i += 1;
                }
                let word =
                    String::from_utf8_lossy(text.get(start..i).unwrap_or_default()).into_owned();
                let tok = if matches!(c, b'0'..=b'9' | b'+' | b'-' | b'.') {
                    Tok::Num(parse_number(&word).ok_or_else(|| {
                        PgtError::at_line(path, line, format!("expected a number, found '{word}'"))
                    })?)
                } else {
                    Tok::Id(word)
                };
                out.push(Token { tok, line });
            }
        }
        if out.len() > MAX_TOKENS {
            return Err(PgtError::at_line(path, line, "too many tokens"));
        }
    }
    Ok(out)
}

fn parse_number(w: &str) -> Option<f64> {
    let (neg, body) = match w.strip_prefix('-') {
        Some(b) => (true, b),
        None => (false, w.strip_prefix('+').unwrap_or(w)),
    };
    let v = if let Some(h) = body.strip_prefix("0x").or_else(|| body.strip_prefix("0X")) {
        u64::from_str_radix(h, 16).ok()? as f64
    } else {
        // Rust accepts "inf"/"nan" words; VRML does not, so require a digit or '.' first.
        if !body.starts_with(|c: char| c.is_ascii_digit() || c == '.') {
            return None;
        }
        body.parse::<f64>().ok()?
    };
    Some(if neg { -v } else { v })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn toks(s: &str) -> Vec<Tok> {
        tokenize(Path::new("t.wrl"), s.as_bytes())
            .expect("ok")
            .into_iter()
            .map(|t| t.tok)
            .collect()
    }

    #[test]
    fn numbers_ids_and_delimiters() {
        assert_eq!(
            toks("Sphere{radius  0.45000}, 0. -1e2 0x1F #c\n _0"),
            vec![
                Tok::Id("Sphere".into()),
                Tok::LBrace,
                Tok::Id("radius".into()),
                Tok::Num(0.45),
                Tok::RBrace,
                Tok::Num(0.0),
                Tok::Num(-100.0),
                Tok::Num(31.0),
                Tok::Id("_0".into()),
            ]
        );
    }

    #[test]
    fn strings_and_errors() {
        assert_eq!(
            toks("\"a \\\"b\\\" # no\""),
            vec![Tok::Str("a \"b\" # no".into())]
        );
        let e = tokenize(Path::new("t.wrl"), b"\n\"abc")
            .expect_err("open")
            .to_string();
        assert!(e.contains("t.wrl:2"), "{e}");
        let e = tokenize(Path::new("t.wrl"), b"1.2.3")
            .expect_err("bad")
            .to_string();
        assert!(e.contains("expected a number"), "{e}");
        let e = tokenize(Path::new("t.wrl"), b"-nan")
            .expect_err("nan")
            .to_string();
        assert!(e.contains("expected a number"), "{e}");
    }
}
