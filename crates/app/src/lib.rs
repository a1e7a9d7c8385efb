//! bounce, the application: the `bounce` command line (`render`, `info`, `compare`, `bench`, `view`, `suite`)
//! and the image files, metrics and plot behind it.
//!
//! [`run`] is the whole command line, so the tests drive it in-process. `cli` is the clap schema,
//! `commands` holds one module per command, and `error` decides the exit code from an error's type:
//! 0 success, 2 bad input (things the user fixes), 1 a runtime failure. Every error is one line on
//! stderr. `output`, `metrics` and `plot` are libraries the tests and tools use too; `light_path` is
//! the scripted light motion of `--light-path` and `--animate`.

pub mod camera_path;
mod cli;
mod commands;
mod error;
pub mod light_path;
pub mod metrics;
pub mod output;
pub mod plot;

use cli::{Cli, Command};
use std::ffi::OsString;
use std::io::Write;

/// The command-line reference (`docs/cli.md`): every command's `--help`, as clap prints it, under a
/// heading each. A test keeps the file equal to it (`BOUNCE_UPDATE_DOCS=1 cargo test cli_reference`
/// rewrites it).
pub fn cli_reference() -> String {
    use clap::CommandFactory;
    let mut cmd = Cli::command().term_width(100);
    // Subcommands name the binary in their usage lines (`bounce render …`) once the tree is built.
    cmd.build();
    let mut md = String::from(
        "# bounce command-line reference\n\nGenerated from the clap schema (`bounce <command> --help`); a test checks it.\n",
    );
    let top = cmd.render_long_help().to_string();
    md += &format!("\n## bounce\n\n```text\n{}\n```\n", top.trim_end());
    let names: Vec<String> = cmd.get_subcommands().map(|c| c.get_name().to_string()).collect();
    for name in names {
        let sub = cmd.find_subcommand_mut(&name).expect("listed above");
        let help = sub.render_long_help().to_string();
        md += &format!("\n## bounce {name}\n\n```text\n{}\n```\n", help.trim_end());
    }
    md
}

/// Runs the command line `args` (program name first); returns the exit code. Output goes to `out`,
/// progress, warnings and the one-line error to `err`.
pub fn run(args: Vec<OsString>, out: &mut dyn Write, err: &mut dyn Write) -> i32 {
    use clap::{CommandFactory, FromArgMatches};
    let named = args.get(1).and_then(|a| a.to_str()).map(str::to_string);
    let parsed = Cli::command()
        .try_get_matches_from(args)
        .and_then(|m| Ok((Cli::from_arg_matches(&m).map_err(|e| e.format(&mut Cli::command()))?, m)));
    let (mut cli, matches) = match parsed {
        Ok(parsed) => parsed,
        // The line's first word names the command whose help the error points to (clap's usage line names
        // it only in some errors; an invalid value's has none).
        Err(e) => return error::report_usage(&e, named.as_deref(), out, err),
    };
    // Which frame flags were given, not defaulted: `render`, `bench` and `suite` say those nothing reads.
    let frame = match &mut cli.command {
        Command::Render(a) => Some(&mut a.frame),
        Command::Bench(a) => Some(&mut a.frame),
        Command::Suite(a) => Some(&mut a.frame),
        Command::View(_) | Command::Info | Command::Compare(_) => None,
    };
    if let (Some(frame), Some((_, m))) = (frame, matches.subcommand()) {
        frame.given = commands::given_settings(m);
    }
    let result = match cli.command {
        Command::Render(a) => commands::render::run(&a, out, err),
        Command::Info => commands::info::run(out),
        Command::Compare(a) => commands::compare::run(&a, out, err),
        Command::Bench(a) => commands::bench::run(&a, out, err),
        Command::View(a) => commands::view::run(&a, out, err),
        Command::Suite(a) => commands::bench::suite::run(&a, out, err),
    };
    match result {
        Ok(()) => error::SUCCESS,
        Err(e) => error::report(&e, err),
    }
}
