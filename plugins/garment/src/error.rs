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
    #[error("{file}:{line}:{col}: {message}")]
    Syntax {
        file: String,
        line: usize,
        col: usize,
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

/// Converts a RON error into [`GarmentError::Syntax`] (its span gives line and column).
pub(crate) fn ron_error(file: &str, e: ron::error::SpannedError) -> GarmentError {
    GarmentError::Syntax {
        file: file.to_owned(),
        line: e.span.start.line,
        col: e.span.start.col,
        message: e.code.to_string(),
    }
}

/// The RON options the garment and fabric files are read with: `Some(..)` may be left out.
pub(crate) fn ron_options() -> ron::Options {
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
    fn line_of_follows_the_path_and_skips_comments() {
        let text = "(\n  // seams: not here\n  panels: [],\n  seams: [\n    (a: (\"front\", \"x\")),\n  ],\n)";
        assert_eq!(line_of(text, &["seams"]), 4);
        assert_eq!(line_of(text, &["seams", "\"front\""]), 5);
        assert_eq!(line_of(text, &["nothing"]), 1);
        // Whole tokens only: `edge` does not match inside `edges`.
        assert_eq!(line_of("edges: 1,\nedge: 2", &["edge"]), 2);
    }
}
