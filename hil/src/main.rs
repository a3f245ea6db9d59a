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
            // `{:#}` prints the context chain on one line: "reading session X: file:line: ...".
            // If standard error itself cannot be written, the exit status is all that is left.
            let _ = writeln!(std::io::stderr().lock(), "error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
