//! Text files split into numbered lines and fields: every text reader takes its lines from
//! here, so a line is the same thing in every format (without its `\n` and a `\r` before it,
//! numbered from 1 as editors number them) and every message names the line a value came from.

use super::source::ByteSource;
use crate::error::Result;
use std::borrow::Cow;

/// A line without its `\n` and a `\r` before it (Windows line ends).
fn strip_cr(line: &[u8]) -> &[u8] {
    line.strip_suffix(b"\r").unwrap_or(line)
}

/// The lines of `bytes`, a piece of a file whose first line is line `first` of the file, with
/// their line numbers. A file that ends with `\n` has an empty last line.
pub fn lines(bytes: &[u8], first: usize) -> impl Iterator<Item = (usize, &[u8])> + '_ {
    bytes
        .split(|&b| b == b'\n')
        .enumerate()
        .map(move |(i, l)| (i + first, strip_cr(l)))
}

/// [`lines`] as text (bytes that are not UTF-8 become U+FFFD).
pub fn text_lines(bytes: &[u8], first: usize) -> impl Iterator<Item = (usize, String)> + '_ {
    lines(bytes, first).map(|(n, l)| (n, String::from_utf8_lossy(l).into_owned()))
}

/// Calls `f(line_number, byte_offset, line)` for every line of a file (numbers and lines as
/// [`lines`] gives them, the offset of the line's first byte), reading it in blocks so that a
/// large file is never in memory at once. `f` returns `false` to stop.
pub fn scan_lines(
    source: &ByteSource,
    mut f: impl FnMut(usize, u64, &[u8]) -> Result<bool>,
) -> Result<()> {
    const BLOCK: u64 = 1 << 20;
    let mut carry: Vec<u8> = Vec::new();
    let mut carry_at = 0u64;
    let mut line_no = 1usize;
    let mut offset = 0u64;
    while offset < source.len() {
        let n = BLOCK.min(source.len() - offset);
        let block = source.read_at(offset, n, "text")?;
        offset += n;
        carry.extend_from_slice(&block);
        let mut start = 0usize;
        while let Some(rel) = carry
            .get(start..)
            .and_then(|s| s.iter().position(|&b| b == b'\n'))
        {
            let line = carry.get(start..start + rel).unwrap_or_default();
            if !f(line_no, carry_at + start as u64, strip_cr(line))? {
                return Ok(());
            }
            line_no += 1;
            start += rel + 1;
        }
        carry.drain(..start);
        carry_at += start as u64;
    }
    if !carry.is_empty() {
        f(line_no, carry_at, strip_cr(&carry))?;
    }
    Ok(())
}

/// Columns `first..=last` of a line (1-based, as format specifications number them), as text;
/// a short line gives what it has (nothing where it ends before `first`).
pub fn columns(line: &[u8], first: usize, last: usize) -> Cow<'_, str> {
    let start = first.saturating_sub(1).min(line.len());
    let end = last.min(line.len());
    String::from_utf8_lossy(line.get(start..end).unwrap_or_default())
}

/// A field that must be a finite number: the number, or the message for the line's error
/// (`expected a number for {what}, found '…'`, `{what} is not finite: '…'`).
pub fn finite_number(text: &str, what: &str) -> std::result::Result<f64, String> {
    match text.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(format!("{what} is not finite: '{text}'")),
        Err(_) => Err(format!("expected a number for {what}, found '{text}'")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn lines_are_numbered_from_the_first_and_lose_their_line_ends() {
        let got: Vec<(usize, &[u8])> = lines(b"ab\r\ncd\n\ne\r", 7).collect();
        let want: Vec<(usize, &[u8])> = vec![(7, b"ab"), (8, b"cd"), (9, b""), (10, b"e")];
        assert_eq!(got, want);
        let text: Vec<(usize, String)> = text_lines(b"x\xffy\n", 1).collect();
        assert_eq!(text, vec![(1, "x\u{fffd}y".into()), (2, String::new())]);
    }

    #[test]
    fn scan_lines_numbers_lines_and_offsets() {
        let b = ByteSource::from_bytes(Path::new("t.txt"), b"ab\r\ncd\n\nlast".to_vec());
        let mut seen = Vec::new();
        scan_lines(&b, |n, at, l| {
            seen.push((n, at, String::from_utf8_lossy(l).into_owned()));
            Ok(n < 3)
        })
        .expect("ok");
        assert_eq!(
            seen,
            vec![
                (1, 0, "ab".into()),
                (2, 4, "cd".into()),
                (3, 7, String::new())
            ],
            "stops where f says, after line 3"
        );
    }

    #[test]
    fn columns_are_one_based_and_inclusive() {
        let line = b"ATOM      2  CA  ALA";
        assert_eq!(columns(line, 1, 6), "ATOM  ");
        assert_eq!(columns(line, 13, 16), " CA ");
        assert_eq!(
            columns(line, 18, 25),
            "ALA",
            "a short line gives what it has"
        );
        assert_eq!(columns(line, 30, 38), "");
        assert_eq!(columns(line, 0, 1), "A");
    }

    #[test]
    fn finite_numbers_or_the_message() {
        assert_eq!(finite_number("-1.5e3", "x"), Ok(-1500.0));
        assert_eq!(
            finite_number("inf", "x"),
            Err("x is not finite: 'inf'".to_string())
        );
        assert_eq!(
            finite_number(" 1", "y"),
            Err("expected a number for y, found ' 1'".to_string())
        );
    }
}
