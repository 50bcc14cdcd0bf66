//! Ctrl-C during `sweep run`, `sweep resume` and `sweep refine`: the process prints how to
//! continue (`wetgran sweep resume NAME --db PATH`) and exits with status 130 (128 + SIGINT, what
//! a shell reports for a process that Ctrl-C stopped).
//!
//! A thread waits for the signal (`signal_hook::iterator::Signals`), writes the message and
//! ends the process. What was committed stays; the jobs that were running keep their rows as
//! `running` under this process's owner name, and the next `sweep resume` re-queues them at
//! once (their process no longer exists: store module doc).

use crate::report::site::shell_word;
use std::path::Path;
use std::sync::Once;

/// The command that continues the sweep `name` (every sweep: `None`) of the database `db`.
pub(super) fn resume_command(name: Option<&str>, db: &Path) -> String {
    let name = name
        .map(|n| format!(" {}", shell_word(n)))
        .unwrap_or_default();
    let db = shell_word(&db.display().to_string());
    format!("wetgran sweep resume{name} --db {db}")
}

/// From now on, Ctrl-C prints how to resume the sweep `name` (all: `None`) of `db` and exits
/// with status 130 (module doc). Only the first call of a process counts.
pub(super) fn resume_hint_on_interrupt(name: Option<&str>, db: &Path) {
    static INSTALLED: Once = Once::new();
    let text = format!(
        "\ninterrupted: the jobs finished so far are stored; those that were running start again \
         on resume. Continue with:\n  {}\n",
        resume_command(name, db)
    );
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
            if signals.forever().next().is_some() {
                use std::io::Write as _;
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
