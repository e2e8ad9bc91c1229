//! The `strafeopt` binary: everything is in the library's `cli` module.

fn main() -> std::process::ExitCode {
    std::process::ExitCode::from(strafeopt::cli::main_with_args(std::env::args_os()))
}
