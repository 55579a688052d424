//! CPU-time clocks for measurements: the calling thread's and the whole process's CPU
//! seconds (POSIX `clock_gettime` with `CLOCK_THREAD_CPUTIME_ID` / `CLOCK_PROCESS_CPUTIME_ID`
//! on Linux: exact to the nanosecond and blind to time spent preempted, so timings hold up on
//! a shared machine). Elsewhere, or if the call fails, the wall time since the first call.

use std::sync::OnceLock;
use std::time::Instant;

/// CPU seconds of the calling thread.
pub fn thread_seconds() -> f64 {
    clock_seconds(3)
}

/// CPU seconds of the whole process, all threads.
pub fn process_seconds() -> f64 {
    clock_seconds(2)
}

/// Wall seconds since the first call of any clock of this module.
fn wall_seconds() -> f64 {
    static START: OnceLock<Instant> = OnceLock::new();
    START.get_or_init(Instant::now).elapsed().as_secs_f64()
}

/// `clock_gettime` of the CPU-time clock `clock` (Linux ids: 2 process, 3 thread) in seconds.
fn clock_seconds(clock: i32) -> f64 {
    #[cfg(target_os = "linux")]
    {
        #[repr(C)]
        struct Timespec {
            tv_sec: i64,
            tv_nsec: i64,
        }
        unsafe extern "C" {
            fn clock_gettime(clock: i32, tp: *mut Timespec) -> i32;
        }
        let mut t = Timespec { tv_sec: 0, tv_nsec: 0 };
        // SAFETY: clock_gettime writes one timespec into the valid, exclusively borrowed `t`.
        if unsafe { clock_gettime(clock, &mut t) } == 0 {
            return t.tv_sec as f64 + 1e-9 * t.tv_nsec as f64;
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = clock;
    wall_seconds()
}

#[cfg(test)]
mod tests {
    /// Both clocks advance with work done on this thread.
    #[test]
    fn clocks_advance_with_work() {
        let (t0, p0) = (super::thread_seconds(), super::process_seconds());
        let mut x = 0.0f64;
        for i in 0..2_000_000 {
            x += (i as f64).sqrt();
        }
        assert!(x > 0.0);
        assert!(super::thread_seconds() > t0 && super::process_seconds() > p0);
    }
}
