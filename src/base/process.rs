//! What the operating system says about this process and machine (Linux `/proc`; `None`
//! elsewhere).

/// The process's peak resident set so far (`VmHWM`), bytes.
pub fn peak_resident_bytes() -> Option<u64> {
    proc_field("/proc/self/status", "VmHWM:").map(|kb| kb * 1024)
}

/// Memory available to new processes (`MemAvailable`), bytes.
pub fn available_memory_bytes() -> Option<u64> {
    proc_field("/proc/meminfo", "MemAvailable:").map(|kb| kb * 1024)
}

/// The number in kB after `key` in a `/proc` file.
fn proc_field(path: &str, key: &str) -> Option<u64> {
    let text = std::fs::read_to_string(path).ok()?;
    let line = text.lines().find(|l| l.starts_with(key))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linux_reports_the_peak_and_the_available_memory() {
        assert!(peak_resident_bytes().is_some_and(|b| b > 1 << 20));
        assert!(available_memory_bytes().is_some_and(|b| b > 1 << 20));
    }
}
