//! The `rigtwin` command. Parsing and dispatch live in [`cli`]; this file only turns
//! an error into a message on stderr and a non-zero exit status.

mod cli;

use std::process::ExitCode;

use clap::Parser as _;

fn main() -> ExitCode {
    let args = cli::Cli::parse();
    match cli::run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // `{:#}` prints the context chain on one line: "reading session X: file:line: ...".
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
