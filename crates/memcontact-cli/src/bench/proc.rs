//! What the operating system tells of the process: peak memory, CPU time, and the CPU time
//! a virtual machine's host took (Linux `/proc`; `None` elsewhere).

/// The process's peak resident set size (`VmHWM` of `/proc/self/status`), in bytes.
pub fn peak_memory() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// CPU seconds used by the process so far, all threads (user + system, from
/// `/proc/self/stat`, one clock tick resolution); `None` where unavailable.
pub fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    let rest = &stat[stat.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let utime: f64 = f.get(11)?.parse().ok()?;
    let stime: f64 = f.get(12)?.parse().ok()?;
    Some((utime + stime) / clock_ticks())
}

/// CPU seconds the hypervisor has taken from this machine's virtual CPUs so far, all CPUs
/// together (`steal` of `/proc/stat`): on a shared virtual machine, time that a benchmark's
/// wall clock includes but that no code of this machine ran in. `None` where unavailable.
pub fn stolen_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/stat").ok()?;
    steal_in_proc_stat(&stat, clock_ticks())
}

/// The `steal` field of the `cpu` line of a `/proc/stat` text, in seconds at `hz` ticks
/// per second.
fn steal_in_proc_stat(text: &str, hz: f64) -> Option<f64> {
    let line = text.lines().find(|l| l.starts_with("cpu "))?;
    // cpu user nice system idle iowait irq softirq steal ...
    let ticks: f64 = line.split_whitespace().nth(8)?.parse().ok()?;
    Some(ticks / hz)
}

/// Clock ticks per second of the `/proc` CPU times (`sysconf(_SC_CLK_TCK)`, 100 where
/// that is unknown).
fn clock_ticks() -> f64 {
    #[cfg(unix)]
    {
        // SAFETY: `sysconf` reads a system constant.
        let hz = unsafe { libc::sysconf(libc::_SC_CLK_TCK) };
        if hz > 0 {
            return hz as f64;
        }
    }
    100.0
}

/// Resets the peak resident set size to the current one (Linux `clear_refs` value 5);
/// silently does nothing where that is not possible.
pub fn reset_peak_memory() {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The steal field is the eighth number of the `cpu` line, not of a `cpuN` line.
    #[test]
    fn steal_is_read_from_the_all_cpu_line() {
        let text = "cpu  6735783 358843 682591 2807773 36520 0 2919 9319 0 0\n\
                    cpu0 3367891 179421 341295 1403886 18260 0 1459 4659 0 0\n\
                    intr 1 2 3\n";
        assert_eq!(steal_in_proc_stat(text, 100.0), Some(93.19));
        assert_eq!(steal_in_proc_stat("cpu0 1 2 3 4 5 6 7 8\n", 100.0), None);
        assert_eq!(steal_in_proc_stat("cpu  1 2 3\n", 100.0), None);
    }
}
