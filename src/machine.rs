//! What this machine lets a run use: memory (the least of what the system has available, the
//! control group's limit and the process's resource limits) and cores. Read from Linux's
//! `/proc` and `/sys`; elsewhere the figures are unknown (None) and nothing is refused on them.

/// Bytes this process can still allocate: the least of MemAvailable, the cgroup's memory limit
/// less its usage (v2 and v1), and the address-space and data-segment limits (`ulimit -v`,
/// `ulimit -d`) less what the process already maps. The address-space figure keeps a quarter
/// in reserve for thread stacks and allocator arenas, which count against it but hold no data.
pub fn available_memory() -> Option<f64> {
    let mut best: Option<f64> = None;
    let mut take = |x: Option<f64>| {
        if let Some(x) = x {
            best = Some(best.map_or(x, |b: f64| b.min(x)));
        }
    };
    take(meminfo("MemAvailable:"));
    take(cgroup_v2().or_else(cgroup_v1));
    let status = std::fs::read_to_string("/proc/self/status").ok();
    let mapped = |key: &str| status.as_deref().and_then(|s| kb_field(s, key));
    if let Some(limit) = rlimit("Max address space") {
        take(Some(
            0.75 * (limit - mapped("VmSize:").unwrap_or(0.0)).max(0.0),
        ));
    }
    if let Some(limit) = rlimit("Max data size") {
        take(Some((limit - mapped("VmData:").unwrap_or(0.0)).max(0.0)));
    }
    best
}

/// The process's peak resident memory so far (VmHWM, bytes), where the system reports it.
pub fn peak_resident_memory() -> Option<u64> {
    status_bytes("VmHWM:")
}

/// The process's resident memory now (VmRSS, bytes), where the system reports it.
pub fn resident_memory() -> Option<u64> {
    status_bytes("VmRSS:")
}

/// Give the allocator's free pages back to the system (glibc's `malloc_trim`; nothing
/// elsewhere), so that the resident memory is what the process holds live. glibc keeps what
/// is freed for later allocations: `strike bench` measured each case's growth of the peak over
/// the resident memory before it, so a case that came after a larger one grew into the freed
/// pages and read 0–133 bytes a particle instead of 800 (2026-12-02: the 16 000-particle cubes
/// after the million-particle cube).
pub fn release_free_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        extern "C" {
            fn malloc_trim(pad: usize) -> std::os::raw::c_int;
        }
        // SAFETY: malloc_trim takes a byte count and only returns free memory of glibc's
        // heaps to the system; it is safe to call at any time from any thread.
        unsafe {
            malloc_trim(0);
        }
    }
}

/// Allocations of this many bytes or more get a mapping of their own from glibc
/// ([`map_large_allocations`]).
pub const MMAP_THRESHOLD: usize = 32 * 1024;

/// Have glibc map every allocation of `MMAP_THRESHOLD` bytes or more on its own and unmap
/// it when it is freed (`mallopt(M_MMAP_THRESHOLD)`; nothing elsewhere), instead of cutting
/// it from its heap. By default glibc raises that threshold to the largest block freed so
/// far (up to 32 MB), so that once the first large array is freed, every block of tens of
/// kB comes from the heap: the packed neighbour lists' chunks (256 particles, about 40 kB in
/// 3D), reallocated as a compressed body's lists grow, and the passes' buffers of the same
/// size, freed between them, left holes that the heap keeps resident. The shocked steel
/// cubes of `strike bench` (16 000 particles, von Mises) peaked 1 292–1 314 bytes a particle
/// above the process before them, 17 % over the heap's peak of 1 074 under heaptrack
/// (2026-12-02); with the threshold fixed at 32 kB, 1 138–1 157 (16 kB: 1 129–1 135;
/// 64 kB: 1 225–1 230), the Johnson–Cook cubes 1 340–1 358 → 1 165–1 198, at the same
/// speed (three interleaved pairs each of the cubes and of the sphere–plate demo); the
/// million-particle cubes' arrays are mapped either way, and the 10⁷-particle cube read 780
/// bytes a particle against 766, at the same speed. Its 39 000 list chunks, each mapped on
/// its own, did not crowd the kernel's table of memory areas (65 530 a process by default):
/// adjacent mappings merge, and the run held at most 57 areas (sampled every half second).
/// Called once, first thing in `main`.
pub fn map_large_allocations() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        extern "C" {
            fn mallopt(
                param: std::os::raw::c_int,
                value: std::os::raw::c_int,
            ) -> std::os::raw::c_int;
        }
        /// glibc's `M_MMAP_THRESHOLD` (malloc.h).
        const M_MMAP_THRESHOLD: std::os::raw::c_int = -3;
        // SAFETY: mallopt only sets a parameter of glibc's allocator; it is safe to call
        // before any thread starts (here: at the top of main).
        unsafe {
            mallopt(M_MMAP_THRESHOLD, MMAP_THRESHOLD as std::os::raw::c_int);
        }
    }
}

fn status_bytes(key: &str) -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    kb_field(&status, key).map(|b| b as u64)
}

/// Cores available to this process.
pub fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |c| c.get())
}

fn meminfo(key: &str) -> Option<f64> {
    kb_field(&std::fs::read_to_string("/proc/meminfo").ok()?, key)
}

/// A "Key:   123 kB" line's value in bytes.
fn kb_field(text: &str, key: &str) -> Option<f64> {
    let line = text.lines().find(|l| l.starts_with(key))?;
    let mut words = line[key.len()..].split_whitespace();
    let value: f64 = words.next()?.parse().ok()?;
    let scale = match words.next() {
        Some("kB") | Some("KB") => 1024.0,
        Some("MB") => 1024.0 * 1024.0,
        _ => 1.0,
    };
    Some(value * scale)
}

fn read_number(path: &str) -> Option<f64> {
    std::fs::read_to_string(path).ok()?.trim().parse().ok()
}

fn cgroup_v2() -> Option<f64> {
    let max = read_number("/sys/fs/cgroup/memory.max")?;
    Some((max - read_number("/sys/fs/cgroup/memory.current").unwrap_or(0.0)).max(0.0))
}

fn cgroup_v1() -> Option<f64> {
    let max = read_number("/sys/fs/cgroup/memory/memory.limit_in_bytes")?;
    // v1 reports "no limit" as a huge number.
    (max < 1e18).then(|| {
        (max - read_number("/sys/fs/cgroup/memory/memory.usage_in_bytes").unwrap_or(0.0)).max(0.0)
    })
}

/// A soft resource limit of this process from /proc/self/limits, in bytes (None: unlimited or
/// unknown).
fn rlimit(name: &str) -> Option<f64> {
    let text = std::fs::read_to_string("/proc/self/limits").ok()?;
    let line = text.lines().find(|l| l.starts_with(name))?;
    line[name.len()..].split_whitespace().next()?.parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_kb_fields() {
        let text = "MemTotal:       24000000 kB\nMemAvailable:    1000 kB\n";
        assert_eq!(kb_field(text, "MemAvailable:"), Some(1000.0 * 1024.0));
        assert_eq!(kb_field(text, "VmSize:"), None);
    }

    #[test]
    fn available_memory_is_positive_on_linux() {
        if cfg!(target_os = "linux") {
            let m = available_memory().expect("Linux has /proc/meminfo");
            assert!(m > 1e6, "{m}");
        }
    }
}
