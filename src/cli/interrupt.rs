//! Ctrl-C during the commands that write a sweep (`sweep run`, `sweep resume`, `sweep refine`,
//! `sweep submit`): the process says what was kept and how to continue, and exits with status
//! 130 (128 + SIGINT, what a shell reports for a process that Ctrl-C stopped).
//!
//! A thread waits for the signal (`signal_hook::iterator::Signals`). While jobs run, it writes
//! how to continue (`wetgran sweep resume NAME --db PATH`) and ends the process: what was
//! committed stays; the jobs that were running keep their rows as `running` under this
//! process's owner name, and the next `sweep resume` re-queues them at once (their process no
//! longer exists: store module doc), and the next writer closes their run rows as interrupted.
//! While a sweep is being registered ([`registering`]), nothing is committed yet: the thread
//! only raises a flag, the registration sees it, rolls its one transaction back and truncates
//! the write-ahead log, and the command then says that nothing was stored. A second Ctrl-C ends
//! the process at once (the transaction dies with it; SQLite drops it on the next open).

use crate::report::site::shell_word;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Mutex, Once};

/// Whether a registration is under way (Ctrl-C then asks it to stop instead of ending the
/// process).
static REGISTERING: AtomicBool = AtomicBool::new(false);
/// Set by Ctrl-C during a registration.
static CANCELLED: AtomicBool = AtomicBool::new(false);
/// What Ctrl-C prints outside a registration (`None`: only that the command was interrupted).
static HINT: Mutex<Option<String>> = Mutex::new(None);

/// The command that continues the sweep `name` (every sweep: `None`) of the database `db`.
pub(super) fn resume_command(name: Option<&str>, db: &Path) -> String {
    let name = name
        .map(|n| format!(" {}", shell_word(n)))
        .unwrap_or_default();
    let db = shell_word(&db.display().to_string());
    format!("wetgran sweep resume{name} --db {db}")
}

/// From now on, Ctrl-C prints how to resume the sweep `name` (all: `None`) of `db` and exits
/// with status 130 (module doc).
pub(super) fn resume_hint_on_interrupt(name: Option<&str>, db: &Path) {
    let text = format!(
        "\ninterrupted: the jobs finished so far are stored; those that were running start again \
         on resume. Continue with:\n  {}\n",
        crate::terminal::escape(&resume_command(name, db))
    );
    *HINT.lock().unwrap_or_else(|e| e.into_inner()) = Some(text);
    watch_for_ctrl_c();
}

/// Runs `register` (a sweep's registration) with Ctrl-C turned into a request to stop: the
/// closure it is given says whether Ctrl-C was pressed (module doc).
pub(super) fn registering<T>(register: impl FnOnce(&dyn Fn() -> bool) -> T) -> T {
    watch_for_ctrl_c();
    CANCELLED.store(false, Ordering::SeqCst);
    REGISTERING.store(true, Ordering::SeqCst);
    let out = register(&|| CANCELLED.load(Ordering::SeqCst));
    REGISTERING.store(false, Ordering::SeqCst);
    out
}

/// Starts the thread that answers Ctrl-C (once per process).
fn watch_for_ctrl_c() {
    static INSTALLED: Once = Once::new();
    INSTALLED.call_once(|| {
        let mut signals = match signal_hook::iterator::Signals::new([signal_hook::consts::SIGINT]) {
            Ok(s) => s,
            Err(e) => {
                // Ctrl-C then stops the process as before, without the hint.
                eprintln!("warning: cannot watch for Ctrl-C: {e}");
                return;
            }
        };
        std::thread::spawn(move || {
            for _ in signals.forever() {
                if REGISTERING.load(Ordering::SeqCst) && !CANCELLED.swap(true, Ordering::SeqCst) {
                    eprintln!(
                        "\ninterrupted: stopping the registration (Ctrl-C again to quit at once)"
                    );
                    continue;
                }
                use std::io::Write as _;
                let text = HINT
                    .lock()
                    .unwrap_or_else(|e| e.into_inner())
                    .clone()
                    .unwrap_or_else(|| "\ninterrupted\n".to_string());
                let mut err = std::io::stderr().lock();
                let _ = err.write_all(text.as_bytes());
                let _ = err.flush();
                std::process::exit(130);
            }
        });
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resume_commands_quote_what_a_shell_would_split() {
        assert_eq!(
            resume_command(Some("quick"), Path::new("runs/w.sqlite")),
            "wetgran sweep resume quick --db runs/w.sqlite"
        );
        assert_eq!(
            resume_command(None, Path::new("my runs/it's.sqlite")),
            r"wetgran sweep resume --db 'my runs/it'\''s.sqlite'"
        );
    }
}
