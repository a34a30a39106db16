//! Real-time scheduling of a haptic servo thread (and its collision thread): what CHAI3D and
//! OpenHaptics applications ask of the system, so that other threads cannot preempt a tick.

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

#[cfg(all(test, target_os = "linux"))]
mod tests {
    use super::*;

    /// The calling thread's scheduling policy.
    fn policy() -> i32 {
        let mut policy = 0;
        let mut p = libc::sched_param { sched_priority: 0 };
        // SAFETY: a plain system call on the current thread with valid out-pointers.
        let r = unsafe { libc::pthread_getschedparam(libc::pthread_self(), &mut policy, &mut p) };
        assert_eq!(r, 0);
        policy
    }

    #[test]
    fn the_answer_says_whether_the_thread_runs_in_real_time() {
        // A thread of its own: the policy stays with it.
        std::thread::spawn(|| {
            // Granted or not (root or CAP_SYS_NICE), the answer is what the system did.
            let granted = realtime_priority(Some(SERVO_PRIORITY));
            assert_eq!(granted, policy() == libc::SCHED_FIFO);
            // Back to the normal scheduler: always allowed.
            assert!(realtime_priority(None));
            assert_eq!(policy(), libc::SCHED_OTHER);
            // A priority out of range is refused, and nothing changes.
            assert!(!realtime_priority(Some(1000)));
            assert_eq!(policy(), libc::SCHED_OTHER);
        })
        .join()
        .unwrap();
    }
}
