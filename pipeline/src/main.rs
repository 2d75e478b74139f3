//! The `ribbar` command line (`pipeline::app`).

fn main() -> std::process::ExitCode {
    std::process::ExitCode::from(pipeline::app::main_with_args(std::env::args_os()))
}
