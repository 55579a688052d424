//! Reading input files: their text (size limit, UTF-8, byte-order mark) and errors located
//! at a file, line, column and field. The floor under `scene`, `garment`, `contact` and
//! `mannequin`, which all read user files and report into the same error type.

mod located;

pub use located::{Locator, SceneError};

/// Largest scene file read (64 MiB): scenes are hand-written text.
pub const MAX_SCENE_BYTES: u64 = 64 << 20;

/// `text` without a leading UTF-8 byte-order mark.
pub fn strip_bom(text: &str) -> &str {
    text.strip_prefix('\u{feff}').unwrap_or(text)
}

/// Scene text from the bytes of `file`: UTF-8 (a byte-order mark allowed), else an error at
/// the line, column and byte offset of the first invalid byte.
pub fn decode(file: &str, bytes: Vec<u8>) -> Result<String, SceneError> {
    String::from_utf8(bytes).map_err(|e| {
        let bytes = e.as_bytes();
        let at = e.utf8_error().valid_up_to();
        let before = &bytes[..at];
        let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
        let line_start = before.iter().rposition(|&b| b == b'\n').map_or(0, |p| p + 1);
        let column = String::from_utf8_lossy(&before[line_start..]).chars().count() + 1;
        SceneError {
            file: file.to_string(),
            line,
            column,
            field: "encoding".into(),
            message: format!("invalid UTF-8 at byte offset {at} (byte 0x{:02x}); scene files must be UTF-8 text", bytes[at]),
        }
    })
}

