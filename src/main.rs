//! The `wetgran` binary: everything lives in the library's `cli` module.

fn main() -> std::process::ExitCode {
    wetgran::cli::main()
}
