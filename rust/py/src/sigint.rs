//! The SIGINT action that lets Ctrl-C stop a kernel running without the GIL (the same
//! action for SIGTERM and SIGHUP, which the command line treats as Ctrl-C).
//!
//! Python's own SIGINT handler only sets a flag that the interpreter reads between
//! bytecodes, so a long kernel would not see it. Before every kernel call ([`ensure`]),
//! the binding makes sure the process's SIGINT action is this module's [`action`]: it
//! sets the kernels' cancel flag ([`gagekit_core::interrupt`]) and then calls the action
//! it replaced (Python's, which sets Python's flag, so the Python handler still runs).
//!
//! Checked at every call, not once: `signal.signal(SIGINT, f)` in Python replaces the
//! process's action (with Python's own again), and the next kernel call puts this one
//! back in front of it. A disposition of SIG_IGN or SIG_DFL (Python's handler set to
//! `signal.SIG_IGN` / `SIG_DFL`, `nohup`, background jobs) is left as it is: Ctrl-C then
//! does what the user or the shell asked for.

#[cfg(unix)]
mod unix {
    use std::sync::atomic::{AtomicUsize, Ordering};

    /// The signals that stop a kernel: Ctrl-C, and SIGTERM and SIGHUP (a timeout, systemd,
    /// `docker stop`, a closed terminal), which the command line treats as Ctrl-C.
    const SIGNALS: [libc::c_int; 3] = [libc::SIGINT, libc::SIGTERM, libc::SIGHUP];

    /// The actions replaced by [`action`], per signal of [`SIGNALS`]: handler address and `sa_flags`.
    static PREV_HANDLER: [AtomicUsize; 3] = [AtomicUsize::new(0), AtomicUsize::new(0), AtomicUsize::new(0)];
    static PREV_FLAGS: [AtomicUsize; 3] = [AtomicUsize::new(0), AtomicUsize::new(0), AtomicUsize::new(0)];

    fn action_addr() -> usize {
        action as *const () as usize
    }

    /// The action: set the cancel flag, then run the replaced action of the same signal.
    /// Only async-signal-safe operations (atomic loads and stores, a call through a pointer).
    extern "C" fn action(sig: libc::c_int, info: *mut libc::siginfo_t, ctx: *mut libc::c_void) {
        gagekit_core::interrupt::request();
        let Some(k) = SIGNALS.iter().position(|&s| s == sig) else { return };
        let prev = PREV_HANDLER[k].load(Ordering::Acquire);
        if prev == libc::SIG_DFL || prev == libc::SIG_IGN || prev == action_addr() {
            return; // not installed over those (see `ensure`)
        }
        let flags = PREV_FLAGS[k].load(Ordering::Relaxed) as libc::c_int;
        // SAFETY: `prev` is the address of the handler the process had installed for
        // this signal, with the calling convention its flags say.
        unsafe {
            if flags & libc::SA_SIGINFO != 0 {
                let f: extern "C" fn(libc::c_int, *mut libc::siginfo_t, *mut libc::c_void) = std::mem::transmute(prev);
                f(sig, info, ctx);
            } else {
                let f: extern "C" fn(libc::c_int) = std::mem::transmute(prev);
                f(sig);
            }
        }
    }

    /// Put [`action`] in front of the current action of each of [`SIGNALS`] unless it is
    /// already there or the disposition is SIG_IGN / SIG_DFL. One `sigaction` call per
    /// signal when nothing changed.
    pub fn ensure() {
        for (k, &sig) in SIGNALS.iter().enumerate() {
            // SAFETY: plain sigaction calls with zeroed, then filled structures.
            unsafe {
                let mut cur: libc::sigaction = std::mem::zeroed();
                if libc::sigaction(sig, std::ptr::null(), &mut cur) != 0 {
                    continue;
                }
                let h = cur.sa_sigaction;
                if h == action_addr() || h == libc::SIG_DFL || h == libc::SIG_IGN {
                    continue;
                }
                PREV_FLAGS[k].store(cur.sa_flags as usize, Ordering::Relaxed);
                PREV_HANDLER[k].store(h, Ordering::Release);
                let mut new: libc::sigaction = std::mem::zeroed();
                new.sa_sigaction = action_addr();
                new.sa_flags = libc::SA_SIGINFO | (cur.sa_flags & libc::SA_ONSTACK);
                new.sa_mask = cur.sa_mask;
                libc::sigaction(sig, &new, std::ptr::null_mut());
            }
        }
    }
}

/// Make Ctrl-C reach the kernels' cancel flag (see the module documentation).
pub fn ensure() {
    #[cfg(unix)]
    unix::ensure();
}
