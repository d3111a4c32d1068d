//! Errors of the garment core. Every message about a file names the file, the line and the
//! field, and says what is accepted.

use std::path::{Path, PathBuf};

/// Why a garment, a fabric or a mesh garment could not be loaded or built.
#[derive(Debug, thiserror::Error)]
pub enum GarmentError {
    /// The file could not be read.
    #[error("cannot read '{}': {source}", path.display())]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    /// A file could not be written.
    #[error("cannot write '{}': {source}", path.display())]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
    /// The RON text does not parse, or a value is refused while it is read (a range check
    /// names the field and the accepted range).
    #[error(
        "{file}:{line}:{col}: {}{message}",
        .field.as_ref().map(|f| format!("in `{f}`: ")).unwrap_or_default()
    )]
    Syntax {
        file: String,
        line: usize,
        col: usize,
        /// The field whose value holds the error, as a path (`sizes[1].length_cm`); `None`
        /// where the error is not inside a field's value (RON's message then names the field,
        /// as for an unknown or a missing one).
        field: Option<String>,
        message: String,
    },
    /// The file parses but its content is inconsistent or out of range.
    #[error("{file}:{line}: `{field}`: {problem}")]
    Invalid {
        file: String,
        line: usize,
        field: String,
        problem: String,
    },
    /// The garment cannot be placed on this body (a landmark or bone is missing, no body at a
    /// wrap's height...).
    #[error("{garment}: cannot place on the body: {problem}")]
    Placement { garment: String, problem: String },
    /// The body could not be measured.
    #[error("cannot measure the body: {0}")]
    Measure(#[from] fitroom_body::MeasureError),
    /// A mesh garment (OBJ+MTL or glTF) is unusable.
    #[error("{file}: {problem}")]
    Mesh { file: String, problem: String },
    /// The cloth core refused the mesh.
    #[error("the cloth core refused the garment mesh: {0}")]
    Cloth(#[from] fitroom_cloth::ClothError),
    /// A slice passed by the caller has the wrong length.
    #[error("expected {expected} {what}, got {got}")]
    LengthMismatch {
        what: &'static str,
        expected: usize,
        got: usize,
    },
}

/// Reads a text file, naming it in the error.
pub(crate) fn read_text(path: &Path) -> Result<String, GarmentError> {
    std::fs::read_to_string(path).map_err(|source| GarmentError::Read {
        path: path.to_owned(),
        source,
    })
}

/// Converts a RON error in `text` into [`GarmentError::Syntax`]: its span gives line and
/// column, and the field whose value holds that position is named ([`field_at`]).
pub(crate) fn ron_error(file: &str, text: &str, e: ron::error::SpannedError) -> GarmentError {
    let (line, col) = (e.span.start.line, e.span.start.col);
    GarmentError::Syntax {
        file: file.to_owned(),
        line,
        col,
        field: field_at(text, line, col),
        message: e.code.to_string(),
    }
}

/// The path of the field whose value holds position `line`:`col` (1-based, columns in
/// characters) of a RON text: the enclosing fields' names joined by `.`, a list element's
/// index in brackets (`sizes[1].length_cm`, a map's key as written: `body_cm."hip"`).
/// `None` if the position is not inside any field's value (a field name itself, or between
/// fields). A forward scan that skips strings and `//` comments; enough for error messages,
/// not a parser.
pub fn field_at(text: &str, line: usize, col: usize) -> Option<String> {
    // Byte offset of the position (clamped to the line's end and the text's end).
    let mut at = text.len();
    let mut start = 0;
    for (k, l) in text.split_inclusive('\n').enumerate() {
        if k + 1 == line {
            let within = l
                .char_indices()
                .nth(col.saturating_sub(1))
                .map_or(l.trim_end_matches('\n').len(), |(i, _)| i);
            at = start + within;
            break;
        }
        start += l.len();
    }
    struct Level {
        /// The field this container is the value of.
        field: Option<String>,
        /// For a list: the elements before the current one.
        list: Option<usize>,
    }
    let mut levels: Vec<Level> = Vec::new();
    let (mut key, mut field): (Option<String>, Option<String>) = (None, None);
    let bytes = text.as_bytes();
    let mut i = 0;
    while i < at {
        match bytes[i] {
            b'/' if bytes.get(i + 1) == Some(&b'/') => {
                while i < at && bytes[i] != b'\n' {
                    i += 1;
                }
                continue;
            }
            b'"' => {
                let open = i;
                i += 1;
                while i < bytes.len() && bytes[i] != b'"' {
                    i += if bytes[i] == b'\\' { 2 } else { 1 };
                }
                key = Some(text[open..(i + 1).min(text.len())].to_owned());
            }
            b'(' | b'{' | b'[' => {
                levels.push(Level {
                    field: field.take(),
                    list: (bytes[i] == b'[').then_some(0),
                });
                key = None;
            }
            b')' | b'}' | b']' => {
                // Back in the field whose value the container was, until the next comma.
                field = levels.pop().and_then(|l| l.field);
                key = None;
            }
            b':' => field = key.take(),
            b',' => {
                (key, field) = (None, None);
                if let Some(Level { list: Some(n), .. }) = levels.last_mut() {
                    *n += 1;
                }
            }
            c if c.is_ascii_alphanumeric() || c == b'_' => {
                let from = i;
                while i + 1 < at && (bytes[i + 1].is_ascii_alphanumeric() || bytes[i + 1] == b'_') {
                    i += 1;
                }
                key = Some(text[from..=i].to_owned());
            }
            _ => {}
        }
        i += 1;
    }
    let mut parts: Vec<String> = Vec::new();
    for level in &levels {
        if let Some(f) = &level.field {
            parts.push(f.clone());
        }
        if let (Some(n), Some(last)) = (level.list, parts.last_mut()) {
            last.push_str(&format!("[{n}]"));
        }
    }
    match field {
        Some(f) => parts.push(f),
        // Not in a field's value at the innermost level.
        None => return None,
    }
    Some(parts.join("."))
}

/// The RON options the garment and fabric files are read with: `Some(..)` may be left out.
pub fn ron_options() -> ron::Options {
    ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
}

/// Finds the line (1-based) of a field or name in a RON text, for errors found after parsing.
///
/// `path` is a chain of needles searched in order, each after the previous one's position,
/// skipping `//` comments: e.g. `["seams", "\"frnt\""]` finds the misspelt panel name in the
/// seams list. Unmatched needles are skipped, so the line of the longest matched prefix is
/// returned (line 1 if nothing matches).
pub(crate) fn line_of(text: &str, path: &[&str]) -> usize {
    // Blank out comments so that needles never match inside them (keep byte offsets).
    let mut code = String::with_capacity(text.len());
    for line in text.split_inclusive('\n') {
        match find_comment(line) {
            Some(at) => {
                code.push_str(&line[..at]);
                code.extend(
                    line[at..]
                        .chars()
                        .map(|c| if c == '\n' { '\n' } else { ' ' }),
                );
            }
            None => code.push_str(line),
        }
    }
    let mut at = 0;
    let mut found = None;
    for needle in path {
        if let Some(rel) = find_token(&code[at..], needle) {
            at += rel;
            found = Some(at);
            at += needle.len();
        }
    }
    match found {
        Some(offset) => code[..offset].matches('\n').count() + 1,
        None => 1,
    }
}

/// Byte offset of a `//` comment start outside string literals.
fn find_comment(line: &str) -> Option<usize> {
    let bytes = line.as_bytes();
    let mut in_string = false;
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'\\' if in_string => i += 1,
            b'"' => in_string = !in_string,
            b'/' if !in_string && bytes.get(i + 1) == Some(&b'/') => return Some(i),
            _ => {}
        }
        i += 1;
    }
    None
}

/// Finds `needle` as a whole token (not inside a longer identifier).
fn find_token(hay: &str, needle: &str) -> Option<usize> {
    let ident = |c: char| c.is_alphanumeric() || c == '_';
    let mut from = 0;
    while let Some(rel) = hay[from..].find(needle) {
        let start = from + rel;
        let end = start + needle.len();
        let before = hay[..start].chars().next_back();
        let after = hay[end..].chars().next();
        let starts_ident = needle.chars().next().is_some_and(ident);
        let ends_ident = needle.chars().next_back().is_some_and(ident);
        if !(starts_ident && before.is_some_and(ident) || ends_ident && after.is_some_and(ident)) {
            return Some(start);
        }
        from = end;
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn field_at_names_the_field_whose_value_holds_a_position() {
        let text = "Garment(\n  name: \"a, b\", // x: (\n  sizes: [\n    (label: \"S\", n: {\"hip\": 9}),\n    (label: \"M\", length_cm: oops),\n  ],\n  fabric: 12,\n)";
        let at = |needle: &str| {
            let (line, l) = text
                .lines()
                .enumerate()
                .find(|(_, l)| l.contains(needle))
                .expect("needle");
            field_at(
                text,
                line + 1,
                l[..l.find(needle).expect("needle")].chars().count() + 1,
            )
        };
        assert_eq!(at("12").as_deref(), Some("fabric"));
        assert_eq!(at("oops").as_deref(), Some("sizes[1].length_cm"));
        assert_eq!(at("9}").as_deref(), Some("sizes[0].n.\"hip\""));
        assert_eq!(at("\"a, b\"").as_deref(), Some("name"));
        // A field's name, and a position between fields: no field.
        assert_eq!(at("fabric"), None);
        assert_eq!(at("(label: \"M\""), None);
        // Past the end of a line: its end, here after the comma that closes `fabric`.
        assert_eq!(field_at(text, 7, 80), None);
        assert_eq!(field_at(text, 7, 12).as_deref(), Some("fabric"));
    }

    #[test]
    fn line_of_follows_the_path_and_skips_comments() {
        let text = "(\n  // seams: not here\n  panels: [],\n  seams: [\n    (a: (\"front\", \"x\")),\n  ],\n)";
        assert_eq!(line_of(text, &["seams"]), 4);
        assert_eq!(line_of(text, &["seams", "\"front\""]), 5);
        assert_eq!(line_of(text, &["nothing"]), 1);
        // Whole tokens only: `edge` does not match inside `edges`.
        assert_eq!(line_of("edges: 1,\nedge: 2", &["edge"]), 2);
    }
}
