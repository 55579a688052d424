//! Resource budget: the memory a scene will need, estimated from the scene alone before any
//! large allocation, against a limit (default: a fraction of the machine's available memory,
//! `--max-memory` overrides).
//!
//! The estimate counts the mesh and model, the tangent (pattern, values and element scatter
//! maps) and the Cholesky factor. The factor of a 2D shell mesh ordered by AMD / nested
//! dissection grows like N log N in the node count N. Calibration (rectangles solved with
//! `plyshell solve`, 5 DOFs per node): factor entries ÷ 25 N log₂ N = 2.73, 3.03, 3.01 for
//! square grids of 10⁴, 4·10⁴, 9·10⁴ nodes (0.94 for a 1000 × 10 strip); peak resident
//! memory 19.7, 20.8, 21.8 KB per node. The estimate uses 3.5 and 3 KB per node for the
//! model and output buffers, so it lies a little above those peaks (22.4 KB per node at
//! 9·10⁴ nodes). All counts use
//! checked arithmetic: an overflow is a refusal, never a wrap.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::OnceLock;

/// Fraction of the available memory a run may plan to use by default.
pub const DEFAULT_FRACTION: f64 = 0.6;

/// Bytes per node of the mesh, model and state vectors (positions, directors, frames, DOF
/// maps, displacement/velocity vectors, export buffers).
const NODE_BYTES: u64 = 3_000;
/// Bytes per element: scatter map (400 × u32), reference geometry, definition.
const ELEMENT_BYTES: u64 = 4_000;
/// Stored tangent entries per node (upper triangle of 5×5 blocks over ~9 neighbours).
const TANGENT_ENTRIES_PER_NODE: u64 = 120;
/// Bytes per stored tangent entry (value and row index, held by the assembler and by faer).
const TANGENT_ENTRY_BYTES: u64 = 32;
/// Factor entries ≈ FACTOR_CONSTANT · 25 · N · log₂ N.
const FACTOR_CONSTANT: f64 = 3.5;

/// 0: no override (use the default fraction of the available memory).
static OVERRIDE: AtomicU64 = AtomicU64::new(0);

/// Sets the memory budget in bytes (`None`: back to the default).
pub fn set_limit(bytes: Option<u64>) {
    OVERRIDE.store(bytes.map_or(0, |b| b.max(1)), Ordering::Relaxed);
}

/// The machine's available memory (`MemAvailable` in /proc/meminfo), in bytes.
pub fn available_bytes() -> Option<u64> {
    static AVAILABLE: OnceLock<Option<u64>> = OnceLock::new();
    *AVAILABLE.get_or_init(|| {
        let s = std::fs::read_to_string("/proc/meminfo").ok()?;
        let line = s.lines().find(|l| l.starts_with("MemAvailable:"))?;
        let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
        kb.checked_mul(1024)
    })
}

/// The memory budget in bytes and where it comes from.
pub fn limit() -> (u64, String) {
    let o = OVERRIDE.load(Ordering::Relaxed);
    if o > 0 {
        return (o, "set by --max-memory".into());
    }
    match available_bytes() {
        Some(a) => ((a as f64 * DEFAULT_FRACTION) as u64, format!("{:.0} % of the {} available; --max-memory overrides", 100.0 * DEFAULT_FRACTION, human(a))),
        // No /proc/meminfo: a conservative fixed budget.
        None => (4 << 30, "the default without /proc/meminfo; --max-memory overrides".into()),
    }
}

/// Parses a size such as `8G`, `512M`, `2.5GiB`, `1000000` (bytes).
pub fn parse_size(s: &str) -> Result<u64, String> {
    let t = s.trim();
    let split = t.find(|c: char| !(c.is_ascii_digit() || c == '.')).unwrap_or(t.len());
    let (num, unit) = t.split_at(split);
    let x: f64 = num.parse().map_err(|_| format!("expected a size such as 8G or 512M, found \"{}\"", s.escape_debug()))?;
    let mult = match unit.trim().to_ascii_lowercase().as_str() {
        "" | "b" => 1.0,
        "k" | "kb" | "kib" => 1024.0,
        "m" | "mb" | "mib" => 1024.0 * 1024.0,
        "g" | "gb" | "gib" => 1024.0 * 1024.0 * 1024.0,
        "t" | "tb" | "tib" => 1024.0f64.powi(4),
        _ => return Err(format!("unknown size unit \"{}\" (use K, M, G or T)", unit.escape_debug())),
    };
    let b = x * mult;
    if !(b.is_finite() && b >= 1.0 && b < 1.8e19) {
        return Err(format!("expected a positive size below 16 EiB, found \"{}\"", s.escape_debug()));
    }
    Ok(b as u64)
}

/// A byte count for messages: `1.5 GiB`.
pub fn human(bytes: u64) -> String {
    let b = bytes as f64;
    if b >= (1u64 << 30) as f64 {
        format!("{:.1} GiB", b / (1u64 << 30) as f64)
    } else if b >= (1u64 << 20) as f64 {
        format!("{:.1} MiB", b / (1u64 << 20) as f64)
    } else {
        format!("{:.0} KiB", b / 1024.0)
    }
}

/// Estimated memory of a model of `nodes` nodes and `elements` shell elements: the mesh and
/// model, the tangent and the Cholesky factor. `None` on overflow.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// Nodes.
    pub nodes: u64,
    /// Elements.
    pub elements: u64,
    /// Mesh, model, state and scatter maps (bytes).
    pub model: u64,
    /// Tangent pattern and values (bytes).
    pub tangent: u64,
    /// Cholesky factor (bytes).
    pub factor: u64,
}

impl Estimate {
    /// The estimate for a model of the given size, `None` when a count overflows.
    pub fn of(nodes: u64, elements: u64) -> Option<Self> {
        let model = nodes.checked_mul(NODE_BYTES)?.checked_add(elements.checked_mul(ELEMENT_BYTES)?)?;
        let tangent = nodes.checked_mul(TANGENT_ENTRIES_PER_NODE)?.checked_mul(TANGENT_ENTRY_BYTES)?;
        let n = nodes.max(2) as f64;
        let factor_entries = FACTOR_CONSTANT * 25.0 * n * n.log2();
        let factor = factor_entries * 8.0;
        if !(factor < 1.8e19) {
            return None;
        }
        Some(Self { nodes, elements, model, tangent, factor: factor as u64 })
    }

    /// Total bytes (saturating).
    pub fn total(&self) -> u64 {
        self.model.saturating_add(self.tangent).saturating_add(self.factor)
    }

    /// "about 3.1 GiB (1200000 nodes: model 1.2 GiB, tangent 0.9 GiB, factor 1.0 GiB)".
    pub fn describe(&self) -> String {
        format!(
            "about {} ({} nodes, {} elements: model {}, tangent {}, factor {})",
            human(self.total()),
            self.nodes,
            self.elements,
            human(self.model),
            human(self.tangent),
            human(self.factor)
        )
    }
}

/// Checks that a model of `nodes` nodes and `elements` elements fits the budget; the error
/// says the estimate and the budget.
pub fn check_model(nodes: u64, elements: u64) -> Result<Estimate, String> {
    let (limit, why) = limit();
    match Estimate::of(nodes, elements) {
        Some(e) if e.total() <= limit => Ok(e),
        Some(e) => Err(format!("the model would need {} but the memory budget is {} ({why})", e.describe(), human(limit))),
        None => Err(format!("the model would have {nodes} nodes and {elements} elements, beyond any memory")),
    }
}

/// Checks that an allocation of `count` items of `item_bytes` bytes fits the budget.
pub fn check_alloc(what: &str, count: u64, item_bytes: u64) -> Result<(), String> {
    let (limit, why) = limit();
    match count.checked_mul(item_bytes) {
        Some(b) if b <= limit => Ok(()),
        Some(b) => Err(format!("{what} would need {} but the memory budget is {} ({why})", human(b), human(limit))),
        None => Err(format!("{what}: {count} items is beyond any memory")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse() {
        assert_eq!(parse_size("512M"), Ok(512 << 20));
        assert_eq!(parse_size("2G"), Ok(2 << 30));
        assert_eq!(parse_size("1.5GiB"), Ok(3 << 29));
        assert_eq!(parse_size("4096"), Ok(4096));
        assert!(parse_size("-1G").is_err() && parse_size("lots").is_err() && parse_size("1e400").is_err() && parse_size("0").is_err());
    }

    #[test]
    fn estimates_overflow_to_none() {
        assert!(Estimate::of(u64::MAX, 1).is_none());
        assert!(Estimate::of(u64::MAX / 100, 1).is_none());
        let e = Estimate::of(10_000, 10_000).expect("small");
        assert!(e.total() > 0 && e.total() < 1 << 30, "{}", e.describe());
    }
}
