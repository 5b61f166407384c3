//! `situate`: see the crate docs of `situate_cli`.

fn main() -> std::process::ExitCode {
    situate_cli::main(std::env::args_os())
}
