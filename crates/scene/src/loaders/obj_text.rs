//! The text of OBJ and MTL files as `tobj` can take it. tobj reads lines as UTF-8 and stops
//! with "read error" at the first line that is not, and with "material parse error" at a
//! material statement without a name; real exporters write both (Latin-1 names from older
//! tools, `newmtl` / `usemtl` with an empty name). So each line is handed over as UTF-8 when
//! it is valid UTF-8 and read as Latin-1 (each byte its own character) when it is not, an
//! empty material name becomes [`UNNAMED`] on both sides (so `usemtl` still finds its
//! `newmtl`), and MTL statements tobj would refuse are mended or dropped.

use std::borrow::Cow;
use std::io::{BufRead, Read};

/// The name given to a material whose `newmtl` / `usemtl` names none.
pub(super) const UNNAMED: &str = "(unnamed)";

/// One line as text: UTF-8 if it is valid UTF-8, else Latin-1.
pub(super) fn decode_line(bytes: &[u8]) -> Cow<'_, str> {
    match std::str::from_utf8(bytes) {
        Ok(s) => Cow::Borrowed(s),
        Err(_) => Cow::Owned(bytes.iter().map(|&b| b as char).collect()),
    }
}

/// A `newmtl` or `usemtl` statement without a name, given [`UNNAMED`]; other lines as they
/// are. `line` has no line ending.
fn name_material(line: &str) -> Option<String> {
    let trimmed = line.trim();
    let keyword = trimmed.split_whitespace().next()?;
    if (keyword == "newmtl" || keyword == "usemtl") && trimmed[keyword.len()..].trim().is_empty() {
        Some(format!("{keyword} {UNNAMED}"))
    } else {
        None
    }
}

/// An OBJ file's bytes, handed to tobj line by line as valid UTF-8 with empty material names
/// filled in (see the module documentation).
pub(super) struct ObjText<R> {
    inner: R,
    /// The current line, decoded, and how much of it was handed out.
    out: Vec<u8>,
    pos: usize,
}

impl<R: BufRead> ObjText<R> {
    pub(super) fn new(inner: R) -> Self {
        Self {
            inner,
            out: Vec::new(),
            pos: 0,
        }
    }
}

impl<R: BufRead> Read for ObjText<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        if self.pos == self.out.len() {
            let mut raw = Vec::new();
            if self.inner.read_until(b'\n', &mut raw)? == 0 {
                return Ok(0);
            }
            let ending = raw
                .iter()
                .rev()
                .take_while(|&&b| b == b'\n' || b == b'\r')
                .count();
            let (body, end) = raw.split_at(raw.len() - ending);
            let text = decode_line(body);
            let named = name_material(&text);
            self.out.clear();
            self.out
                .extend_from_slice(named.as_deref().unwrap_or(&text).as_bytes());
            self.out.extend_from_slice(end);
            self.pos = 0;
        }
        let n = buf.len().min(self.out.len() - self.pos);
        buf[..n].copy_from_slice(&self.out[self.pos..self.pos + n]);
        self.pos += n;
        Ok(n)
    }
}

/// Rewrites what tobj 4.0.5 would refuse or panic on in a material library: lines in Latin-1
/// (read as such), `newmtl` without a name ([`UNNAMED`]), texture and `illum` statements
/// without an argument (dropped: tobj fails the whole library on them), and colour statements
/// with fewer than three numbers (tobj unwraps three after `Ka`, `Kd`, `Ks` and `Ke`, found
/// by fuzzing: the MTL specification lets green and blue default to red, so `Kd 0.5` is grey,
/// and a colour statement with no number is dropped so the material keeps its default).
pub(super) fn sanitize_mtl(bytes: &[u8]) -> Vec<u8> {
    let mut out = String::with_capacity(bytes.len());
    for raw in bytes.split(|&b| b == b'\n') {
        let text = decode_line(raw);
        let line = text.trim_end_matches('\r');
        if let Some(named) = name_material(line) {
            out.push_str(&named);
            out.push('\n');
            continue;
        }
        let mut words = line.split_whitespace();
        let keyword = words.next();
        if matches!(keyword, Some("Ka" | "Kd" | "Ks" | "Ke")) {
            let values: Vec<&str> = words.by_ref().take(3).collect();
            match values.len() {
                0 => continue,
                1 | 2 => {
                    let r = values[0];
                    let g = values.get(1).copied().unwrap_or(r);
                    out.push_str(&format!("{} {r} {g} {r}\n", keyword.unwrap_or_default()));
                    continue;
                }
                _ => {}
            }
        }
        let needs_argument = keyword.is_some_and(|k| {
            k.starts_with("map_") || k == "bump" || k == "illum" || k == "disp" || k == "decal"
        });
        if needs_argument && words.next().is_none() {
            continue;
        }
        out.push_str(line);
        out.push('\n');
    }
    out.into_bytes()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_become_utf8_and_names_are_filled_in() {
        let obj = b"o Caf\xe9\r\nusemtl\nusemtl  \t\nusemtl m\nv 1 2 3";
        let mut text = String::new();
        ObjText::new(&obj[..]).read_to_string(&mut text).unwrap();
        assert_eq!(
            text,
            "o Café\r\nusemtl (unnamed)\nusemtl (unnamed)\nusemtl m\nv 1 2 3"
        );
        let mtl =
            String::from_utf8(sanitize_mtl(b"newmtl\nKd 0.5\nmap_Kd\nnewmtl \xc9t\xe9\n")).unwrap();
        assert_eq!(mtl, "newmtl (unnamed)\nKd 0.5 0.5 0.5\nnewmtl Été\n\n");
    }
}
