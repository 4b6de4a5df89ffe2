//! This thread's CPU time, for the examples' timings on a shared machine.

/// This thread's CPU time (user + system), seconds, from `/proc/thread-self/stat`
/// (clock ticks of 10 ms): on a shared machine it counts this run's work, not the time
/// it waited for a core. `None` off Linux.
pub fn cpu() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/thread-self/stat").ok()?;
    let rest = &s[s.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}
