//! [`AfError`]: the first mistake in a Doom 3 text file, with its `FILE:LINE:COL`, the
//! one error of the `.af`, `.md5mesh`, `.md5anim` and `.def` readers and of the
//! [`lexer`](super::lexer) they share; and [`read_text`], how each of them reads a file.

use super::lexer::Pos;
use std::fmt;
use std::path::Path;

/// The first mistake in a file: where, and what was expected.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AfError {
    /// The file as named to the reader.
    pub file: String,
    /// 1-based line.
    pub line: u32,
    /// 1-based column.
    pub col: u32,
    /// What is wrong; says what was expected and what was found where that helps.
    pub message: String,
}

impl AfError {
    /// An error at `pos` of `file`. Control characters in the message (a stray byte
    /// quoted from the file, a newline) are escaped so the error stays one visible line.
    pub(crate) fn at(file: &str, pos: Pos, message: String) -> AfError {
        AfError {
            file: file.to_string(),
            line: pos.line,
            col: pos.col,
            message: escape_controls(&message),
        }
    }
}

/// `s` with every control character written as Rust escapes it (`\n`, `\u{1}`).
fn escape_controls(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_control() {
                c.escape_debug().to_string()
            } else {
                c.to_string()
            }
        })
        .collect()
}

impl fmt::Display for AfError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}:{}:{}: error: {}",
            self.file, self.line, self.col, self.message
        )
    }
}

impl std::error::Error for AfError {}

/// Reads a text file for one of the Doom 3 readers; `what` names it in the error.
pub(crate) fn read_text(path: &Path, what: &str) -> Result<String, AfError> {
    let bytes = std::fs::read(path).map_err(|e| AfError {
        file: path.display().to_string(),
        line: 1,
        col: 1,
        message: format!("cannot read the {what}: {e}"),
    })?;
    // idLexer reads bytes; text outside UTF-8 is taken as Latin-1 rather than refused.
    Ok(match String::from_utf8(bytes) {
        Ok(s) => s,
        Err(e) => e.into_bytes().iter().map(|&b| b as char).collect(),
    })
}
