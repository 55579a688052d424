//! Scene errors that point at a file, line, column and field.

use std::fmt;

/// An error in a scene file.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneError {
    /// Scene file path as given.
    pub file: String,
    /// 1-based line (0 when the place is unknown).
    pub line: usize,
    /// 1-based column (0 when the place is unknown).
    pub column: usize,
    /// Field path, e.g. `parts[strip].thickness`.
    pub field: String,
    /// What is wrong and what was expected.
    pub message: String,
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.line > 0 {
            write!(f, "{}:{}:{}: {}: {}", self.file, self.line, self.column, self.field, self.message)
        } else {
            write!(f, "{}: {}: {}", self.file, self.field, self.message)
        }
    }
}

impl std::error::Error for SceneError {}

/// Finds positions of names and fields in the scene text, for semantic errors found after
/// parsing (serde does not keep spans).
#[derive(Clone, Debug)]
pub struct Locator<'a> {
    file: &'a str,
    text: &'a str,
}

impl<'a> Locator<'a> {
    /// A locator over the text of `file`.
    pub fn new(file: &'a str, text: &'a str) -> Self {
        Self { file, text }
    }

    fn line_col(&self, offset: usize) -> (usize, usize) {
        let before = &self.text[..offset.min(self.text.len())];
        let line = before.matches('\n').count() + 1;
        let col = before.rfind('\n').map(|p| offset - p).unwrap_or(offset + 1);
        (line, col)
    }

    /// Byte offset of the first `"name"` at or after `from`.
    fn find_quoted(&self, name: &str, from: usize) -> Option<usize> {
        let needle = format!("\"{name}\"");
        self.text.get(from..)?.find(&needle).map(|p| p + from)
    }

    /// Byte offset of the first `key:` (as a whole word) at or after `from`.
    fn find_key(&self, key: &str, from: usize) -> Option<usize> {
        let mut start = from;
        while let Some(p) = self.text.get(start..)?.find(key) {
            let at = start + p;
            let before_ok = at == 0 || !self.text.as_bytes()[at - 1].is_ascii_alphanumeric() && self.text.as_bytes()[at - 1] != b'_';
            let rest = self.text[at + key.len()..].trim_start();
            if before_ok && rest.starts_with(':') {
                return Some(at);
            }
            start = at + key.len();
        }
        None
    }

    /// An error located at the `key:` that follows the quoted `anchor` (or at the anchor, or
    /// nowhere when neither is found).
    pub fn at(&self, anchor: Option<&str>, key: Option<&str>, field: impl Into<String>, message: impl Into<String>) -> SceneError {
        let anchor_pos = anchor.and_then(|a| self.find_quoted(a, 0));
        let pos = match (anchor_pos, key) {
            (Some(a), Some(k)) => self.find_key(k, a).or(Some(a)),
            (Some(a), None) => Some(a),
            (None, Some(k)) => self.find_key(k, 0),
            (None, None) => None,
        };
        let (line, column) = pos.map(|p| self.line_col(p)).unwrap_or((0, 0));
        SceneError { file: self.file.to_string(), line, column, field: field.into(), message: message.into() }
    }

    /// An error located at a quoted value that follows the quoted `anchor`.
    pub fn at_value(&self, anchor: &str, value: &str, field: impl Into<String>, message: impl Into<String>) -> SceneError {
        let a = self.find_quoted(anchor, 0).unwrap_or(0);
        let pos = self.find_quoted(value, a + anchor.len() + 2).or_else(|| self.find_quoted(value, 0));
        let (line, column) = pos.map(|p| self.line_col(p)).unwrap_or((0, 0));
        SceneError { file: self.file.to_string(), line, column, field: field.into(), message: message.into() }
    }

    /// Converts a RON parse error (syntax or type) to a located error.
    pub fn from_ron(&self, e: &ron::error::SpannedError) -> SceneError {
        SceneError {
            file: self.file.to_string(),
            line: e.span.start.line,
            column: e.span.start.col,
            field: "syntax".into(),
            message: e.code.to_string(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_field_after_anchor() {
        let text = "parts: [\n  (name: \"a\", thickness: 1.0),\n  (name: \"b\", thickness: -1.0),\n]";
        let l = Locator::new("s.ron", text);
        let e = l.at(Some("b"), Some("thickness"), "parts[b].thickness", "must be positive");
        assert_eq!((e.line, e.column), (3, 15));
        assert_eq!(e.to_string(), "s.ron:3:15: parts[b].thickness: must be positive");
    }
}
