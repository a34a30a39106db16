//! Facts about the running process and machine, for benchmark reports.

/// Peak resident memory of this process in bytes (Linux `VmHWM`), if known.
pub fn peak_memory_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// A one-line description of the CPU (model name and logical core count), if known.
pub fn cpu_description() -> String {
    let model = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    let cores = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1);
    format!("{model}, {cores} logical cores")
}

/// Real-time FIFO priority of the haptic servo thread (Linux: 1 to 99; CHAI3D and the
/// viewer's loop use the same).
pub const SERVO_PRIORITY: i32 = 20;

/// Puts the calling thread under real-time FIFO scheduling at `priority` (`Some`), as haptic
/// servo loops do, or back under the normal scheduler (`None`); true when the change was
/// granted (root or CAP_SYS_NICE on Linux), false elsewhere. Threads it spawns afterwards
/// inherit the policy.
pub fn realtime_priority(priority: Option<i32>) -> bool {
    #[cfg(target_os = "linux")]
    {
        let (policy, level) = match priority {
            Some(p) => (libc::SCHED_FIFO, p),
            None => (libc::SCHED_OTHER, 0),
        };
        let p = libc::sched_param {
            sched_priority: level,
        };
        // SAFETY: a plain system call on the current thread with a valid parameter.
        unsafe { libc::pthread_setschedparam(libc::pthread_self(), policy, &p) == 0 }
    }
    #[cfg(not(target_os = "linux"))]
    {
        let _ = priority;
        false
    }
}
