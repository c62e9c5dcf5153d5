//! The dotted key path (`body[1].shape.center[2]`) at a byte offset of a TOML text, for errors
//! that `toml` reports with a span but no key. A small lexer, forgiving of anything it does not
//! understand: it only has to name the key near a span, not to parse TOML.

use std::collections::HashMap;

#[derive(Debug, Clone, PartialEq)]
enum Tok {
    /// Bare word: a bare or dotted key, a number, a boolean, a date.
    Word(String),
    /// Quoted string (content, roughly unescaped).
    Str(String),
    Punct(char),
    Newline,
}

fn lex(text: &str) -> Vec<(usize, Tok)> {
    let bytes = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        let c = bytes[i];
        match c {
            b' ' | b'\t' | b'\r' => i += 1,
            b'\n' => {
                out.push((i, Tok::Newline));
                i += 1;
            }
            b'#' => {
                while i < bytes.len() && bytes[i] != b'\n' {
                    i += 1;
                }
            }
            b'=' | b',' | b'[' | b']' | b'{' | b'}' => {
                out.push((i, Tok::Punct(c as char)));
                i += 1;
            }
            b'"' | b'\'' => {
                let start = i;
                let triple = text[i..].starts_with(if c == b'"' { "\"\"\"" } else { "'''" });
                let (open, close): (usize, &[u8]) = if triple {
                    (3, if c == b'"' { b"\"\"\"" } else { b"'''" })
                } else {
                    (1, if c == b'"' { b"\"" } else { b"'" })
                };
                i += open;
                let content_start = i;
                let mut content_end = bytes.len();
                while i < bytes.len() {
                    if c == b'"' && bytes[i] == b'\\' {
                        i += 2;
                        continue;
                    }
                    if !triple && bytes[i] == b'\n' {
                        content_end = i;
                        break;
                    }
                    if bytes[i..].starts_with(close) {
                        content_end = i;
                        i += close.len();
                        break;
                    }
                    i += 1;
                }
                let content = text
                    .get(content_start..content_end.min(bytes.len()))
                    .unwrap_or("")
                    .to_string();
                out.push((start, Tok::Str(content)));
            }
            _ => {
                let start = i;
                while i < bytes.len()
                    && !matches!(
                        bytes[i],
                        b' ' | b'\t'
                            | b'\r'
                            | b'\n'
                            | b'#'
                            | b'='
                            | b','
                            | b'['
                            | b']'
                            | b'{'
                            | b'}'
                            | b'"'
                            | b'\''
                    )
                {
                    i += 1;
                }
                out.push((start, Tok::Word(text[start..i].to_string())));
            }
        }
    }
    out
}

#[derive(Debug, Clone)]
enum Seg {
    Key(String),
    Index(usize),
}

fn render(path: &[Seg]) -> String {
    let mut s = String::new();
    for seg in path {
        match seg {
            Seg::Key(k) => {
                if !s.is_empty() {
                    s.push('.');
                }
                let bare = !k.is_empty()
                    && k.chars()
                        .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
                if bare {
                    s.push_str(k);
                } else {
                    s.push_str(&format!("{k:?}"));
                }
            }
            Seg::Index(i) => s.push_str(&format!("[{i}]")),
        }
    }
    s
}

/// Key segments of a (possibly dotted) key made of words and quoted strings.
fn key_segments(parts: &[Tok]) -> Vec<String> {
    let mut out = Vec::new();
    for part in parts {
        match part {
            Tok::Word(w) => out.extend(
                w.split('.')
                    .filter(|s| !s.is_empty())
                    .map(|s| s.to_string()),
            ),
            Tok::Str(s) => out.push(s.clone()),
            _ => {}
        }
    }
    out
}

enum Frame {
    /// Inside `{ … }`: the path of the table and the key being read.
    Inline {
        base: Vec<Seg>,
        key: Vec<Tok>,
        in_value: bool,
    },
    /// Inside `[ … ]` (a value): the path of the array and the element index.
    Array { base: Vec<Seg>, index: usize },
}

/// The frame a value opening with `{` (an inline table) or `[` (an array) starts at `base`.
fn open_frame(opening: char, base: Vec<Seg>) -> Frame {
    if opening == '{' {
        Frame::Inline {
            base,
            key: Vec::new(),
            in_value: false,
        }
    } else {
        Frame::Array { base, index: 0 }
    }
}

/// The dotted key path naming what is at byte `offset` of `text` (empty at the top level).
pub fn key_path_at(text: &str, offset: usize) -> String {
    let tokens = lex(text);
    // Header state.
    let mut header: Vec<Seg> = Vec::new();
    let mut array_index: HashMap<String, usize> = HashMap::new();
    // Top-level key/value state.
    let mut key: Vec<Tok> = Vec::new();
    let mut in_value = false;
    let mut value_path: Vec<Seg> = Vec::new();
    let mut frames: Vec<Frame> = Vec::new();
    let mut best = String::new();

    let mut t = 0;
    while t < tokens.len() {
        let (pos, tok) = &tokens[t];
        if *pos > offset {
            break;
        }
        // Table header at the start of a line.
        if frames.is_empty() && !in_value && key.is_empty() && *tok == Tok::Punct('[') {
            let double = matches!(tokens.get(t + 1), Some((_, Tok::Punct('['))));
            let mut j = t + if double { 2 } else { 1 };
            let mut parts = Vec::new();
            while j < tokens.len() && !matches!(tokens[j].1, Tok::Punct(']') | Tok::Newline) {
                parts.push(tokens[j].1.clone());
                j += 1;
            }
            let names = key_segments(&parts);
            // Resolve the path, inserting the current index of every array of tables.
            let mut path = Vec::new();
            let mut plain = String::new();
            for (n, name) in names.iter().enumerate() {
                if !plain.is_empty() {
                    plain.push('.');
                }
                plain.push_str(name);
                path.push(Seg::Key(name.clone()));
                if double && n + 1 == names.len() {
                    let next = array_index.get(&plain).map_or(0, |i| i + 1);
                    let prefix = format!("{plain}.");
                    array_index.retain(|k, _| !k.starts_with(&prefix));
                    array_index.insert(plain.clone(), next);
                    path.push(Seg::Index(next));
                } else if let Some(&i) = array_index.get(&plain) {
                    path.push(Seg::Index(i));
                }
            }
            header = path;
            best = render(&header);
            // Skip to the end of the line.
            while j < tokens.len() && tokens[j].1 != Tok::Newline {
                j += 1;
            }
            t = j;
            continue;
        }
        match frames.last_mut() {
            None => match tok {
                Tok::Newline => {
                    key.clear();
                    in_value = false;
                    best = render(&header);
                }
                Tok::Punct('=') if !in_value => {
                    in_value = true;
                    value_path = header.clone();
                    value_path.extend(key_segments(&key).into_iter().map(Seg::Key));
                    best = render(&value_path);
                }
                Tok::Word(_) | Tok::Str(_) if !in_value => {
                    key.push(tok.clone());
                    let mut p = header.clone();
                    p.extend(key_segments(&key).into_iter().map(Seg::Key));
                    best = render(&p);
                }
                Tok::Punct('{') if in_value => frames.push(Frame::Inline {
                    base: value_path.clone(),
                    key: Vec::new(),
                    in_value: false,
                }),
                Tok::Punct('[') if in_value => {
                    let mut p = value_path.clone();
                    p.push(Seg::Index(0));
                    best = render(&value_path);
                    frames.push(Frame::Array {
                        base: value_path.clone(),
                        index: 0,
                    });
                    // The element path is set on the next token.
                    let _ = p;
                }
                _ => {}
            },
            Some(Frame::Inline {
                base,
                key,
                in_value,
            }) => match tok {
                Tok::Punct('}') => {
                    let b = base.clone();
                    frames.pop();
                    best = render(&b);
                }
                Tok::Punct(',') => {
                    key.clear();
                    *in_value = false;
                    best = render(base);
                }
                Tok::Punct('=') if !*in_value => {
                    *in_value = true;
                    let mut p = base.clone();
                    p.extend(key_segments(key).into_iter().map(Seg::Key));
                    best = render(&p);
                }
                Tok::Word(_) | Tok::Str(_) if !*in_value => {
                    key.push(tok.clone());
                    let mut p = base.clone();
                    p.extend(key_segments(key).into_iter().map(Seg::Key));
                    best = render(&p);
                }
                Tok::Punct(c @ ('{' | '[')) if *in_value => {
                    let mut p = base.clone();
                    p.extend(key_segments(key).into_iter().map(Seg::Key));
                    best = render(&p);
                    frames.push(open_frame(*c, p));
                }
                _ => {}
            },
            Some(Frame::Array { base, index }) => match tok {
                Tok::Punct(']') => {
                    let b = base.clone();
                    frames.pop();
                    best = render(&b);
                }
                Tok::Punct(',') => {
                    *index += 1;
                    best = render(base);
                }
                Tok::Newline => {}
                Tok::Punct(c @ ('{' | '[')) => {
                    let mut p = base.clone();
                    p.push(Seg::Index(*index));
                    best = render(&p);
                    frames.push(open_frame(*c, p));
                }
                _ => {
                    let mut p = base.clone();
                    p.push(Seg::Index(*index));
                    best = render(&p);
                }
            },
        }
        t += 1;
    }
    best
}

#[cfg(test)]
mod tests {
    use super::key_path_at;

    fn at(text: &str, needle: &str) -> String {
        key_path_at(text, text.find(needle).unwrap())
    }

    #[test]
    fn paths_through_headers_inline_tables_and_arrays() {
        let text = "[simulation]\ndimension = 3 # [x]\n\n[materials.al]\ndensity = \"a\"\n\
                    [[body]]\nname = \"a\"\n[[body]]\nname = \"b\"\nspacng = 1\n\
                    shape = { type = \"box\", min = [0, 0, \"z\"], max = [1, 1, 1] }\n\
                    [[output.picture]]\ntimes = [\n  0.0,\n  \"t\",\n]\n";
        assert_eq!(at(text, "3 #"), "simulation.dimension");
        assert_eq!(at(text, "\"a\"\n["), "materials.al.density");
        assert_eq!(at(text, "spacng"), "body[1].spacng");
        assert_eq!(at(text, "\"z\""), "body[1].shape.min[2]");
        assert_eq!(at(text, "max"), "body[1].shape.max");
        assert_eq!(at(text, "\"t\""), "output.picture[0].times[1]");
        assert_eq!(at(text, "[[body]]\nname = \"b\""), "body[1]");
    }
}
