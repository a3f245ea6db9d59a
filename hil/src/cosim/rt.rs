//! What a real-time loop asks of the operating system: a fixed-priority (SCHED_FIFO)
//! thread, locked memory (no page fault in the loop), and the finest timer slack. Each
//! is a request the OS may refuse (an unprivileged user, a container without
//! `CAP_SYS_NICE` or `CAP_IPC_LOCK`); the error is one line that says what was refused
//! and what it means, and the loop runs on without it.

use thread_priority::{
    RealtimeThreadSchedulePolicy, ThreadPriority, ThreadPriorityValue, ThreadSchedulePolicy,
    set_thread_priority_and_policy, thread_native_id,
};

/// Runs the calling thread under SCHED_FIFO at `priority` (1–99), with a timer slack of
/// 1 ns (the kernel's default of 50 µs would be a fifth of a 4 kHz period).
///
/// # Errors
/// One line saying what the OS refused.
pub fn set_fifo_priority(priority: u8) -> Result<(), String> {
    // Timer slack applies to every thread; refusing it is harmless, so it is not reported.
    let _ = nix::sys::prctl::set_timerslack(1);
    let value = ThreadPriorityValue::try_from(priority)
        .map_err(|e| format!("--rt-priority {priority}: {e}; use 1-99"))?;
    set_thread_priority_and_policy(
        thread_native_id(),
        ThreadPriority::Crossplatform(value),
        ThreadSchedulePolicy::Realtime(RealtimeThreadSchedulePolicy::Fifo),
    )
    .map_err(|e| {
        format!(
            "--rt-priority {priority}: SCHED_FIFO refused by the OS ({e:?}); running at normal priority (needs root or CAP_SYS_NICE, and an rtprio limit)"
        )
    })
}

/// Locks the process's current and future memory in RAM (mlockall), so the loop never
/// waits for a page.
///
/// # Errors
/// One line saying what the OS refused.
pub fn lock_memory() -> Result<(), String> {
    use nix::sys::mman::{MlockAllFlags, mlockall};
    use nix::sys::resource::{RLIM_INFINITY, Resource, getrlimit};
    // With a finite memlock limit, MCL_FUTURE would turn the first allocation past it
    // into an allocation failure (an abort); lock only where the limit cannot bite.
    let (soft, _) = getrlimit(Resource::RLIMIT_MEMLOCK).map_err(|e| {
        format!("--lock-memory: reading RLIMIT_MEMLOCK failed ({e}); memory stays pageable")
    })?;
    if !nix::unistd::geteuid().is_root() && soft != RLIM_INFINITY {
        return Err(format!(
            "--lock-memory: the memlock limit is {} KiB, too small to lock a growing process; memory stays pageable (raise it with ulimit -l unlimited, or run as root)",
            soft / 1024
        ));
    }
    mlockall(MlockAllFlags::MCL_CURRENT | MlockAllFlags::MCL_FUTURE).map_err(|e| {
        format!(
            "--lock-memory: mlockall refused by the OS ({e}); memory stays pageable (needs root or CAP_IPC_LOCK, and a memlock limit)"
        )
    })
}
