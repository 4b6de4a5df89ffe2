//! Every array the package allocates itself, sized and checked before it is made: a
//! size past counting, a call whose arrays together exceed this machine's memory, or
//! an allocation the system refuses is a `MemoryError` naming the bytes, never the
//! allocator's abort of the whole interpreter (Rust's default on a failed allocation).
//!
//! A call first adds up what it will hold at once ([`Need`]) and checks the total
//! against the machine's memory and swap, so that nothing is computed (a dense
//! mobility of 40,000 spheres is minutes of work) before a refusal; each array is then
//! reserved with `try_reserve_exact`, which catches what the total check cannot see
//! (memory other processes hold, limits set by `ulimit`).

use hydrorattle_host::sizing::human;
use pyo3::exceptions::PyMemoryError;
use pyo3::prelude::*;

/// The arrays one call holds at once, by name: their bytes, or `None` for a size past
/// counting (the arithmetic overflowed).
pub struct Need {
    what: String,
    parts: Vec<(&'static str, Option<usize>)>,
}

/// The blocks of a packed symmetric matrix of `n` block rows (`tri(n)`), `None` past
/// counting.
pub fn packed(n: usize) -> Option<usize> {
    n.checked_mul(n.checked_add(1)?).map(|x| x / 2)
}

/// `count` values of `T`, in bytes (`None` past counting).
pub fn bytes_of<T>(count: Option<usize>) -> Option<usize> {
    count?.checked_mul(std::mem::size_of::<T>())
}

impl Need {
    /// What the call is, for the message (`"mobility of 40000 spheres"`).
    pub fn new(what: impl Into<String>) -> Self {
        Need {
            what: what.into(),
            parts: Vec::new(),
        }
    }

    /// Adds `count` values of `T` called `name`.
    pub fn add<T>(mut self, name: &'static str, count: Option<usize>) -> Self {
        self.parts.push((name, bytes_of::<T>(count)));
        self
    }

    /// The total, checked against the machine's memory and swap where known.
    pub fn check(&self) -> PyResult<()> {
        let total = self
            .parts
            .iter()
            .try_fold(0usize, |s, &(_, b)| s.checked_add(b?));
        let shown = |b: Option<usize>| b.map_or_else(|| "more than 16 EiB".into(), bytes);
        let parts = || {
            let each: Vec<String> = self
                .parts
                .iter()
                .map(|&(name, b)| format!("{name} {}", shown(b)))
                .collect();
            each.join(", ")
        };
        let Some(total) = total else {
            return Err(PyMemoryError::new_err(format!(
                "{} needs more memory than can be counted ({})",
                self.what,
                parts()
            )));
        };
        match machine_memory() {
            Some(have) if total as u64 > have => Err(PyMemoryError::new_err(format!(
                "{} needs {} ({}), more than this machine's {} of memory and swap",
                self.what,
                bytes(total),
                parts(),
                human(have)
            ))),
            _ => Ok(()),
        }
    }
}

/// `bytes` as the CLI's storage messages print them (`53.6 GiB`).
fn bytes(b: usize) -> String {
    human(b as u64)
}

/// A vector of `count` copies of `value` (`name` and `what` for the message), reserved
/// first: a `MemoryError` naming its size where the allocator refuses it.
pub fn filled<T: Clone>(what: &str, name: &str, count: usize, value: T) -> PyResult<Vec<T>> {
    let mut v = Vec::new();
    if v.try_reserve_exact(count).is_err() {
        let size = bytes_of::<T>(Some(count)).map_or_else(|| "more than 16 EiB".into(), bytes);
        return Err(PyMemoryError::new_err(format!(
            "{what}: the {name} ({size}) could not be allocated"
        )));
    }
    v.resize(count, value);
    Ok(v)
}

/// This machine's memory and swap in bytes (Linux's `/proc/meminfo`); `None` where it
/// cannot be read (the allocations are then only reserved, each checked on its own).
fn machine_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let kib = |key: &str| -> Option<u64> {
        let line = text.lines().find(|l| l.starts_with(key))?;
        line.split_whitespace().nth(1)?.parse().ok()
    };
    let total = kib("MemTotal:")?.checked_add(kib("SwapTotal:").unwrap_or(0))?;
    total.checked_mul(1024)
}
