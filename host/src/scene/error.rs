//! Scene errors, placed in their file: `origin:line:col: message`.

use std::fmt;
use std::ops::Range;

use crate::sizing::TooLarge;

/// A scene that could not be read, parsed or accepted.
///
/// Displays as `origin:line:col: message` when the error has a place in the file, and
/// as `origin: message` otherwise (for example when the file cannot be read).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SceneError {
    /// Where the text came from, usually the file's path.
    pub origin: String,
    /// 1-based line and column (in characters) of the offending text, if known.
    pub location: Option<(usize, usize)>,
    /// What is wrong.
    pub message: String,
    /// The storage refusal, when the scene is too large to run (the message says the
    /// same in words).
    pub too_large: Option<TooLarge>,
}

impl SceneError {
    /// The 1-based line of the error, if it has one.
    pub fn line(&self) -> Option<usize> {
        self.location.map(|(line, _)| line)
    }
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.location {
            Some((line, col)) => write!(f, "{}:{}:{}: {}", self.origin, line, col, self.message),
            None => write!(f, "{}: {}", self.origin, self.message),
        }
    }
}

impl std::error::Error for SceneError {}

/// Converts a byte offset in `text` to a 1-based (line, column), columns in characters.
pub fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let col = before[line_start..].chars().count() + 1;
    (line, col)
}

/// A semantic error before it is placed in a file: a message and a byte span.
pub(super) struct Issue {
    pub(super) span: Option<Range<usize>>,
    pub(super) message: String,
    pub(super) too_large: Option<TooLarge>,
}

impl Issue {
    /// An error with no place in the file (a missing table).
    pub(super) fn unplaced(message: impl Into<String>) -> Issue {
        Issue {
            span: None,
            message: message.into(),
            too_large: None,
        }
    }
}

/// A storage refusal placed at the value that set the count.
pub(super) fn too_large(span: Range<usize>, e: TooLarge) -> Issue {
    Issue {
        span: Some(span),
        message: e.to_string(),
        too_large: Some(e),
    }
}

pub(super) fn issue(span: Range<usize>, message: impl Into<String>) -> Issue {
    Issue {
        span: Some(span),
        message: message.into(),
        too_large: None,
    }
}
