//! The `rigtwin` command. Parsing and dispatch live in [`cli`]; this file only turns
//! an error into a message on stderr and a non-zero exit status.

mod cli;

use std::io::Write as _;
use std::process::ExitCode;

use clap::Parser as _;

fn main() -> ExitCode {
    let args = cli::Cli::parse();
    match cli::run(&args).and_then(|()| Ok(cli::out::flush()?)) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // A reader that went away (`rigtwin diagnose ... | head`): whatever the command
            // records is already on disk and there is nobody left to tell. Exit quietly,
            // as a filter killed by SIGPIPE would.
            if e.downcast_ref::<cli::out::OutputError>()
                .is_some_and(cli::out::OutputError::is_broken_pipe)
            {
                return ExitCode::SUCCESS;
            }
            // If standard error itself cannot be written, the exit status is all that is left.
            let _ = writeln!(std::io::stderr().lock(), "error: {}", one_line(&e));
            ExitCode::FAILURE
        }
    }
}

/// The error and its causes on one line, "reading session X: file:line: ...", each cause
/// once: many errors already show their source in their own text (`{file}: {source}`),
/// and `{:#}` would print it again after them.
fn one_line(e: &anyhow::Error) -> String {
    let mut text = e.to_string();
    for cause in e.chain().skip(1) {
        let c = cause.to_string();
        if !text.contains(&c) {
            text.push_str(": ");
            text.push_str(&c);
        }
    }
    text
}
