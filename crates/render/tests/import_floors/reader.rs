//! Reading Rust source as the floors check needs it: comments and literals out, tokens,
//! `#[cfg(test)]` items out, then the `use` items and `a::b` paths of one file ([`refs`]).

fn is_ident_char(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// The source without comments, with every string and character literal emptied and raw
/// identifiers (`r#virtual`) written plainly.
pub fn strip_comments_and_literals(src: &str) -> String {
    let c: Vec<char> = src.chars().collect();
    let n = c.len();
    let at = |i: usize| c.get(i).copied().unwrap_or('\0');
    let mut out = String::with_capacity(n);
    let mut i = 0;
    while i < n {
        let ch = c[i];
        let prev_ident = i > 0 && is_ident_char(c[i - 1]);
        if ch == '/' && at(i + 1) == '/' {
            while i < n && c[i] != '\n' {
                i += 1;
            }
        } else if ch == '/' && at(i + 1) == '*' {
            let mut depth = 0;
            while i < n {
                if c[i] == '/' && at(i + 1) == '*' {
                    depth += 1;
                    i += 2;
                } else if c[i] == '*' && at(i + 1) == '/' {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
            out.push(' ');
        } else if ch == 'r' && !prev_ident && (at(i + 1) == '#' || at(i + 1) == '"') {
            let mut j = i + 1;
            let mut hashes = 0;
            while at(j) == '#' {
                hashes += 1;
                j += 1;
            }
            if at(j) == '"' {
                // Raw string: ends at a quote followed by as many hashes.
                j += 1;
                while j < n {
                    if c[j] == '"' && (1..=hashes).all(|k| at(j + k) == '#') {
                        j += 1 + hashes;
                        break;
                    }
                    j += 1;
                }
                out.push_str("\"\"");
                i = j;
            } else if hashes == 1 && is_ident_char(at(j)) {
                // Raw identifier: the name without `r#`.
                i = j;
            } else {
                out.push(ch);
                i += 1;
            }
        } else if ch == 'b' && !prev_ident && at(i + 1) == '"' {
            i += 1; // a byte string: the string below
        } else if ch == '"' {
            i += 1;
            while i < n && c[i] != '"' {
                i += if c[i] == '\\' { 2 } else { 1 };
            }
            i += 1;
            out.push_str("\"\"");
        } else if ch == '\'' {
            if at(i + 1) == '\\' {
                // Escaped character literal: up to the closing quote.
                let mut j = i + 2;
                while j < n && c[j] != '\'' {
                    j += 1;
                }
                i = j + 1;
                out.push_str("' '");
            } else if at(i + 2) == '\'' {
                i += 3;
                out.push_str("' '");
            } else {
                out.push(ch); // a lifetime
                i += 1;
            }
        } else {
            out.push(ch);
            i += 1;
        }
    }
    out
}

/// Identifiers, `::`, and single punctuation characters.
pub fn tokenize(code: &str) -> Vec<String> {
    let c: Vec<char> = code.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < c.len() {
        if is_ident_char(c[i]) {
            let start = i;
            while i < c.len() && is_ident_char(c[i]) {
                i += 1;
            }
            out.push(c[start..i].iter().collect());
        } else if c[i] == ':' && c.get(i + 1) == Some(&':') {
            out.push("::".into());
            i += 2;
        } else {
            if !c[i].is_whitespace() {
                out.push(c[i].to_string());
            }
            i += 1;
        }
    }
    out
}

pub fn is_ident(t: &str) -> bool {
    t.chars()
        .next()
        .is_some_and(|c| c.is_alphabetic() || c == '_')
}

/// Index just past the group that opens at `i` (`{`, `(` or `[`), nesting counted.
pub fn skip_group(t: &[String], i: usize) -> usize {
    let (open, close) = match t[i].as_str() {
        "{" => ("{", "}"),
        "(" => ("(", ")"),
        _ => ("[", "]"),
    };
    let mut depth = 0;
    let mut j = i;
    while j < t.len() {
        if t[j] == open {
            depth += 1;
        } else if t[j] == close {
            depth -= 1;
            if depth == 0 {
                return j + 1;
            }
        }
        j += 1;
    }
    t.len()
}

/// Removes every item under `#[cfg(test)]`; returns the remaining tokens and the names of
/// file modules declared test-only (`#[cfg(test)] mod name;`).
pub fn strip_test_items(t: Vec<String>) -> (Vec<String>, Vec<String>) {
    const ATTR: [&str; 7] = ["#", "[", "cfg", "(", "test", ")", "]"];
    let mut out = Vec::with_capacity(t.len());
    let mut test_modules = Vec::new();
    let mut i = 0;
    while i < t.len() {
        if t.len() - i < ATTR.len() || t[i..i + ATTR.len()].iter().zip(ATTR).any(|(a, b)| a != b) {
            out.push(t[i].clone());
            i += 1;
            continue;
        }
        let mut j = i + ATTR.len();
        // Further attributes of the same item.
        while j + 1 < t.len() && t[j] == "#" && t[j + 1] == "[" {
            j = skip_group(&t, j + 1);
        }
        let item_start = j;
        // The item ends at a `;` outside brackets, or with its first `{ … }` (and a `;` after
        // it, as in `use a::{b, c};`).
        while j < t.len() {
            match t[j].as_str() {
                "(" | "[" => j = skip_group(&t, j),
                "{" => {
                    j = skip_group(&t, j);
                    if t.get(j).is_some_and(|s| s == ";") {
                        j += 1;
                    }
                    break;
                }
                ";" => {
                    j += 1;
                    break;
                }
                _ => j += 1,
            }
        }
        let item = &t[item_start..j];
        if let Some(k) = item.iter().position(|s| s == "mod") {
            if item.len() == k + 3 && item[k + 2] == ";" {
                test_modules.push(item[k + 1].clone());
            }
        }
        i = j;
    }
    (out, test_modules)
}

/// One name a `use` brings in: its path, the name it is known by (`None` for a glob).
#[derive(Debug)]
pub struct UseItem {
    pub path: Vec<String>,
    pub name: Option<String>,
}

/// The items of the use tree in `t` (the tokens between `use` and `;`).
pub fn parse_use_tree(t: &[String], pos: &mut usize, prefix: Vec<String>, out: &mut Vec<UseItem>) {
    let mut path = prefix;
    while *pos < t.len() {
        let tok = t[*pos].as_str();
        match tok {
            "::" => *pos += 1, // a leading `::`
            "{" => {
                *pos += 1;
                while *pos < t.len() && t[*pos] != "}" {
                    parse_use_tree(t, pos, path.clone(), out);
                    if t.get(*pos).is_some_and(|s| s == ",") {
                        *pos += 1;
                    }
                }
                *pos += 1;
                return;
            }
            "*" => {
                *pos += 1;
                out.push(UseItem { path, name: None });
                return;
            }
            _ if is_ident(tok) => {
                *pos += 1;
                if tok != "self" {
                    path.push(tok.to_string());
                }
                if t.get(*pos).is_some_and(|s| s == "::") {
                    *pos += 1;
                    continue;
                }
                let mut name = path.last().cloned();
                if t.get(*pos).is_some_and(|s| s == "as") {
                    name = t.get(*pos + 1).cloned();
                    *pos += 2;
                }
                out.push(UseItem { path, name });
                return;
            }
            _ => {
                *pos += 1;
                return;
            }
        }
    }
}

/// What one file refers to.
#[derive(Debug, Default)]
pub struct Refs {
    /// `use` items, each with the inline modules (`mod x { … }`) it is written in.
    pub uses: Vec<(Vec<String>, UseItem)>,
    /// Paths of two or more segments outside `use`, with their inline modules.
    pub paths: Vec<(Vec<String>, Vec<String>)>,
    /// File modules declared under `#[cfg(test)]`.
    pub test_modules: Vec<String>,
}

pub fn refs(src: &str) -> Refs {
    let (t, test_modules) = strip_test_items(tokenize(&strip_comments_and_literals(src)));
    let mut r = Refs {
        test_modules,
        ..Default::default()
    };
    let mut scope: Vec<(String, usize)> = Vec::new();
    let mut depth = 0usize;
    let mut i = 0;
    while i < t.len() {
        let tok = t[i].as_str();
        let names = |scope: &[(String, usize)]| scope.iter().map(|s| s.0.clone()).collect();
        if tok == "mod" && t.get(i + 2).is_some_and(|s| s == "{") && is_ident(&t[i + 1]) {
            scope.push((t[i + 1].clone(), depth));
            depth += 1;
            i += 3;
        } else if tok == "{" {
            depth += 1;
            i += 1;
        } else if tok == "}" {
            depth = depth.saturating_sub(1);
            if scope.last().is_some_and(|s| s.1 == depth) {
                scope.pop();
            }
            i += 1;
        } else if tok == "use" {
            let end = (i..t.len()).find(|&j| t[j] == ";").unwrap_or(t.len());
            let mut items = Vec::new();
            let mut pos = 0;
            parse_use_tree(&t[i + 1..end], &mut pos, Vec::new(), &mut items);
            let here: Vec<String> = names(&scope);
            r.uses.extend(items.into_iter().map(|u| (here.clone(), u)));
            i = end + 1;
        } else if is_ident(tok)
            && (i == 0 || t[i - 1] != "::")
            && t.get(i + 1).is_some_and(|s| s == "::")
            && t.get(i + 2).is_some_and(|s| is_ident(s))
        {
            let mut segs = vec![tok.to_string()];
            let mut j = i;
            while t.get(j + 1).is_some_and(|s| s == "::")
                && t.get(j + 2).is_some_and(|s| is_ident(s))
            {
                segs.push(t[j + 2].clone());
                j += 2;
            }
            r.paths.push((names(&scope), segs));
            i = j + 1;
        } else {
            i += 1;
        }
    }
    r
}
