//! `situate-gen c|cpp MANIFEST [-o DIR]`: writes a skill's typed I/O (see
//! `situate_cabi::gen`). Prints the written paths. The `situate` program's
//! `situate gen` does the same; the CMake package uses either.

use std::path::PathBuf;
use std::process::ExitCode;

use situate_cabi::{generate, write_generated, Lang};

const USAGE: &str = "usage: situate-gen c|cpp MANIFEST [-o DIR]";

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut positional = Vec::new();
    let mut out_dir = PathBuf::from(".");
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "-o" | "--out" => match it.next() {
                Some(d) => out_dir = PathBuf::from(d),
                None => {
                    eprintln!("situate-gen: `-o` needs a directory\n{USAGE}");
                    return ExitCode::from(2);
                }
            },
            "-h" | "--help" => {
                println!("{USAGE}");
                return ExitCode::SUCCESS;
            }
            _ => positional.push(a.clone()),
        }
    }
    let [lang, manifest] = &positional[..] else {
        eprintln!("situate-gen: expected a language and a manifest\n{USAGE}");
        return ExitCode::from(2);
    };
    let Some(lang) = Lang::parse(lang) else {
        eprintln!("situate-gen: {}\n{USAGE}", Lang::unknown(lang));
        return ExitCode::from(2);
    };
    let files = match generate(lang, manifest.as_ref()) {
        Ok(files) => files,
        Err(e) => {
            eprintln!("situate-gen: error: {e}");
            return ExitCode::FAILURE;
        }
    };
    match write_generated(&files, &out_dir) {
        Ok(paths) => paths.iter().for_each(|p| println!("{}", p.display())),
        Err(e) => {
            eprintln!("situate-gen: error: {e}");
            return ExitCode::FAILURE;
        }
    }
    ExitCode::SUCCESS
}
