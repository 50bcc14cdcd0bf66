//! The `wetgran` binary: everything lives in the library's `cli` module.

fn main() -> std::process::ExitCode {
    quiet_on_closed_pipe();
    wetgran::cli::main()
}

/// `wetgran export | head`: when the reader closes the pipe, printing fails and `println!`
/// panics. That is not an error of wetgran's: leave quietly with the status a shell reports for
/// SIGPIPE (128 + 13), and keep the normal panic report for everything else.
fn quiet_on_closed_pipe() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let message = info
            .payload()
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| info.payload().downcast_ref::<&str>().copied())
            .unwrap_or("");
        if message.starts_with("failed printing to stdout") && message.contains("Broken pipe") {
            std::process::exit(141);
        }
        default(info);
    }));
}
