//! `my-situate`: the whole `situate` program (every command, the built-in skill types) plus this
//! crate's own skill types, which robot files name like the built-in ones and `my-situate types`
//! lists.

mod skills;

fn main() -> std::process::ExitCode {
    let ext = situate_cli::Extensions::default().skills(|registry| {
        registry.register::<skills::Nearest>().register::<skills::Brake>();
    });
    std::process::ExitCode::from(situate_cli::main_with(std::env::args_os(), ext))
}
