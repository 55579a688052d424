//! Input errors that point at a file, line, column and field.

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

/// `s` with control characters escaped (`\0`, `\n`, `\u{1b}`), so a message never
/// carries raw control bytes to the terminal.
fn printable(s: &str) -> String {
    s.chars().map(|c| if c.is_control() { c.escape_default().to_string() } else { c.to_string() }).collect()
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (file, field, message) = (printable(&self.file), printable(&self.field), printable(&self.message));
        if self.line > 0 {
            write!(f, "{file}:{}:{}: {field}: {message}", self.line, self.column)
        } else {
            write!(f, "{file}: {field}: {message}")
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

    /// Byte offset of the first `"name"` at or after `from`, with the name as written
    /// verbatim or with its quotes, backslashes and control characters escaped.
    fn find_quoted(&self, name: &str, from: usize) -> Option<usize> {
        let rest = self.text.get(from..)?;
        let plain = name.chars().all(|c| !(c.is_control() || c == '"' || c == '\\' || !c.is_ascii()));
        let mut forms = vec![name.to_string()];
        if !plain {
            forms.push(name.escape_debug().to_string());
            forms.push(name.escape_default().to_string());
            forms.push(name.chars().map(|c| if c.is_control() { format!("\\x{:02x}", c as u32) } else { c.escape_debug().to_string() }).collect());
            forms.push(name.chars().map(|c| if c.is_ascii() && !c.is_control() { c.escape_debug().to_string() } else { c.escape_unicode().to_string() }).collect());
        }
        forms.iter().filter_map(|f| rest.find(&format!("\"{f}\""))).min().map(|p| p + from)
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

    /// An error located at the quoted `name` as written in the file: verbatim, or with its
    /// quotes, backslashes and control characters escaped (`\"`, `\\`, `\0`, `\u{..}`,
    /// `\x..`); else at the first occurrence of its longest plain run of characters.
    pub fn at_name(&self, name: &str, field: impl Into<String>, message: impl Into<String>) -> SceneError {
        let mut forms = vec![name.to_string(), name.escape_debug().to_string(), name.escape_default().to_string()];
        forms.push(name.chars().map(|c| if c.is_control() { format!("\\x{:02x}", c as u32) } else { c.escape_debug().to_string() }).collect());
        let mut pos = forms.iter().find_map(|f| self.find_quoted(f, 0));
        if pos.is_none() {
            let plain = name.split(|c: char| c.is_control() || c == '"' || c == '\\').max_by_key(|s| s.len()).unwrap_or("");
            if !plain.is_empty() {
                pos = self.text.find(plain).map(|p| self.text[..p].rfind('"').unwrap_or(p));
            } else if name.is_empty() {
                pos = self.text.find("\"\"");
            }
        }
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

    /// Byte offset of a 1-based line and (character) column.
    fn offset_of(&self, line: usize, col: usize) -> usize {
        let start = if line <= 1 { 0 } else { self.text.match_indices('\n').nth(line - 2).map_or(self.text.len(), |(p, _)| p + 1) };
        self.text[start..].char_indices().nth(col.saturating_sub(1)).map_or(self.text.len(), |(p, _)| start + p)
    }

    /// The key (`name:` or `"name":`) whose value holds byte `offset`, and the key of the
    /// map or struct holding that, by scanning back over balanced brackets. A comma at the
    /// value's level means the offset is a new entry, not a value: keys at that level are
    /// then skipped.
    fn keys_before(&self, offset: usize) -> Vec<String> {
        let b = self.text.as_bytes();
        let mut keys = Vec::new();
        let (mut depth, mut skip) = (0usize, false);
        let mut i = offset.min(b.len());
        while i > 0 && keys.len() < 2 {
            i -= 1;
            match b[i] {
                b')' | b']' | b'}' => depth += 1,
                b'(' | b'[' | b'{' => {
                    if depth == 0 {
                        skip = false;
                    } else {
                        depth -= 1;
                    }
                }
                b',' if depth == 0 => skip = true,
                b':' if depth == 0 && !skip => {
                    let before = self.text[..i].trim_end();
                    let key = if let Some(q) = before.strip_suffix('"') {
                        q.rfind('"').map(|p| format!("[{}]", &q[p + 1..]))
                    } else {
                        let start = before.char_indices().rev().find(|&(_, c)| !(c.is_alphanumeric() || c == '_')).map_or(0, |(p, c)| p + c.len_utf8());
                        (start < before.len()).then(|| before[start..].to_string())
                    };
                    if let Some(k) = key {
                        keys.push(k);
                        // Continue above this key's entry.
                        skip = true;
                    }
                }
                _ => {}
            }
        }
        keys
    }

    /// The literal starting at byte `offset` (up to a delimiter), for messages.
    fn token_at(&self, offset: usize) -> &str {
        let rest = self.text.get(offset..).unwrap_or("").trim_start();
        let end = rest.find(|c: char| matches!(c, ',' | ')' | ']' | '}' | '\n') || c.is_whitespace()).unwrap_or(rest.len());
        let end = rest.char_indices().nth(40).map_or(end, |(p, _)| end.min(p));
        &rest[..end]
    }

    /// Start of the value whose key ends before byte `offset` on the same line, if any.
    fn value_start(&self, offset: usize) -> Option<usize> {
        let line_start = self.text[..offset.min(self.text.len())].rfind('\n').map_or(0, |p| p + 1);
        let colon = self.text[line_start..offset.min(self.text.len())].rfind(':')? + line_start;
        let v = colon + 1 + (self.text[colon + 1..].len() - self.text[colon + 1..].trim_start().len());
        (v <= offset).then_some(v)
    }

    /// Converts a RON parse error (syntax or type) to a located error that names the field
    /// (the nearest enclosing keys) and, for a value of the wrong type, what was expected
    /// and found ("expected an integer, found 2.5").
    pub fn from_ron(&self, e: &ron::error::SpannedError) -> SceneError {
        use ron::error::Error as E;
        let (line, column) = (e.span.start.line, e.span.start.col);
        let offset = self.offset_of(line, column);
        let keys = self.keys_before(offset);
        let field = match keys.as_slice() {
            [] => "syntax".to_string(),
            [k] => k.clone(),
            [k, parent, ..] if k.starts_with('[') => format!("{parent}{k}"),
            [k, parent, ..] => format!("{parent}.{k}"),
        };
        let value = self.value_start(offset).map(|v| self.token_at(v)).unwrap_or("");
        let number = |t: &str| t.parse::<f64>().is_ok() || t.starts_with(|c: char| c.is_ascii_digit() || c == '-' || c == '+' || c == '.');
        let message = match &e.code {
            E::IntegerOutOfBounds => format!("expected an integer in range (a count or index ≥ 0), found {value}"),
            E::InvalidIntegerDigit { .. } | E::ExpectedInteger => format!("expected an integer, found {}", if value.is_empty() { self.token_at(offset) } else { value }),
            E::ExpectedComma | E::ExpectedStructLikeEnd | E::ExpectedArrayEnd | E::ExpectedMapEnd
                if !value.is_empty() && number(value) && value.parse::<i128>().is_err() && self.text[offset..].starts_with(['.', 'e', 'E']) =>
            {
                format!("expected an integer, found {value}")
            }
            E::ExpectedFloat => format!("expected a number, found {}", self.token_at(offset)),
            E::ExpectedString | E::ExpectedStringEnd => format!("expected a quoted string, found {}", self.token_at(offset)),
            other => {
                let within = if field == "syntax" { String::new() } else { format!(" (after `{field}`)") };
                return SceneError { file: self.file.to_string(), line, column, field: "syntax".into(), message: format!("{other}{within}") };
            }
        };
        SceneError { file: self.file.to_string(), line, column, field, message }
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
