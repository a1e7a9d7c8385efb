//! The exit-code policy, decided by the *type* of an error, and the one-line error report.
//!
//! - [`SUCCESS`] (0): the command did what it was asked (and `--help`, `--version`).
//! - [`BAD_INPUT`] (2): something the user fixes by changing the input or the machine: an argument clap
//!   rejects, a scene that does not load ([`SceneError`]), settings the device or scene cannot run
//!   ([`SettingsError`]), an
//!   unreadable input image ([`BadInput`]), no usable Vulkan device or validation layer (the
//!   [`bounce_device::Error`] variants of [`device_missing`]).
//! - [`RUNTIME`] (1): everything else: a Vulkan call that failed, an output that cannot be written, …
//!
//! Every error is one line on stderr, starting with `error: `.

use bounce_graph::frame::SettingsError;
use bounce_graph::scene::SceneError;
use std::io::Write;

pub const SUCCESS: i32 = 0;
pub const RUNTIME: i32 = 1;
pub const BAD_INPUT: i32 = 2;

/// An error the user can fix by changing the input: the app's own input checks. It shows the wrapped
/// error's own message and passes its causes on as its source, so [`report`] sees the whole chain.
#[derive(Debug)]
pub struct BadInput(anyhow::Error);

impl std::fmt::Display for BadInput {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        std::fmt::Display::fmt(&self.0, f)
    }
}

impl std::error::Error for BadInput {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        self.0.source()
    }
}

/// Marks `e` as bad input (exit code 2).
pub fn bad(e: impl Into<anyhow::Error>) -> anyhow::Error {
    anyhow::Error::new(BadInput(e.into()))
}

/// The device errors that mean "no usable device here" (the machine lacks a driver, a layer, a
/// feature) rather than a failure of a device that works.
pub fn device_missing(e: &bounce_device::Error) -> bool {
    use bounce_device::Error as E;
    matches!(
        e,
        E::Loader(_) | E::NoDevice(_) | E::NoMatchingDevice { .. } | E::MissingFeature { .. } | E::NoValidationLayer
    )
}

/// A device error for the report: a missing device speaks for itself; any other failure says what
/// was being done.
pub fn device(e: bounce_device::Error) -> anyhow::Error {
    if device_missing(&e) {
        e.into()
    } else {
        anyhow::Error::new(e).context("creating the Vulkan device")
    }
}

/// The exit code of a failed command: [`BAD_INPUT`] when any error in the chain is one of the input
/// types, else [`RUNTIME`].
pub fn exit_code(e: &anyhow::Error) -> i32 {
    let bad_input = e.chain().any(|cause| {
        cause.is::<BadInput>()
            || cause.is::<SceneError>()
            || cause.is::<SettingsError>()
            || cause.downcast_ref::<bounce_device::Error>().is_some_and(device_missing)
    });
    if bad_input {
        BAD_INPUT
    } else {
        RUNTIME
    }
}

/// Writes `e` as one `error:` line on `err` and returns its exit code: the chain of causes, outermost
/// first, joined by ": ". A cause whose text already ends its wrapper's (an error that prints its source
/// and also returns it from `source()`, as `SceneError::Io` and exr's I/O errors do) is said once.
pub fn report(e: &anyhow::Error, err: &mut dyn Write) -> i32 {
    let mut one_line = String::new();
    for cause in e.chain() {
        let text = cause.to_string().replace('\n', " ");
        if one_line.ends_with(&text) {
            continue;
        }
        if !one_line.is_empty() {
            one_line.push_str(": ");
        }
        one_line.push_str(&text);
    }
    // Nothing is left to tell the user if stderr itself fails; the exit code still says it.
    let _ = writeln!(err, "error: {one_line}");
    exit_code(e)
}

/// A command line clap rejected (exit 2, one line on `err`), or `--help` / `--version` (exit 0, the
/// text on `out`). `named`: the line's first word, the command whose help the error points to where it
/// is one.
pub fn report_usage(e: &clap::Error, named: Option<&str>, out: &mut dyn Write, err: &mut dyn Write) -> i32 {
    let text = e.render().to_string();
    if !e.use_stderr() {
        let _ = write!(out, "{text}");
        return SUCCESS;
    }
    if e.kind() == clap::error::ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand {
        // No command: clap's help, whose first paragraph is the program's tagline, not an error.
        let _ =
            writeln!(err, "error: no command given: render, info, compare, bench, view or suite (see `bounce --help`)");
        return BAD_INPUT;
    }
    // The command's own help where the usage line names one (`Usage: bounce render …`).
    let command = text
        .lines()
        .find_map(|l| l.trim().strip_prefix("Usage: bounce "))
        .and_then(|rest| rest.split_whitespace().next())
        .filter(|c| !c.starts_with(['[', '<', '-']))
        .or_else(|| {
            use clap::CommandFactory;
            named.filter(|n| crate::cli::Cli::command().get_subcommands().any(|c| c.get_name() == *n))
        });
    let help = command.map_or("bounce --help".to_string(), |c| format!("bounce {c} --help"));
    // clap's message is several paragraphs; the first names the problem (and, for missing arguments,
    // lists them on its following lines). One line, like every error.
    let lines = text.lines().skip_while(|l| l.trim().is_empty());
    let first: Vec<&str> = lines.take_while(|l| !l.trim().is_empty()).map(str::trim).collect();
    let first = if first.is_empty() { "invalid arguments".to_string() } else { first.join(" ") };
    let _ = writeln!(err, "error: {} (see `{help}`)", first.trim_start_matches("error: ").trim());
    BAD_INPUT
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn scene_error() -> SceneError {
        SceneError::Invalid { path: PathBuf::from("s.toml"), msg: "no light".into() }
    }

    #[test]
    fn input_errors_are_bad_input_wherever_they_sit_in_the_chain() {
        assert_eq!(exit_code(&scene_error().into()), BAD_INPUT);
        assert_eq!(exit_code(&anyhow::Error::new(scene_error()).context("loading")), BAD_INPUT);
        assert_eq!(exit_code(&bad(anyhow::anyhow!("--regions must be a perfect square"))), BAD_INPUT);
        let missing = bounce_device::Error::NoDevice(String::new());
        assert_eq!(exit_code(&device(missing)), BAD_INPUT);
        assert_eq!(exit_code(&device(bounce_device::Error::NoValidationLayer)), BAD_INPUT);
    }

    #[test]
    fn other_errors_are_runtime_failures() {
        assert_eq!(exit_code(&anyhow::anyhow!("vkQueueSubmit failed")), RUNTIME);
        let failed = bounce_device::Error::Vk { call: "vkCreateDevice", result: ash::vk::Result::ERROR_DEVICE_LOST };
        let e = device(failed);
        assert_eq!(exit_code(&e), RUNTIME);
        assert!(format!("{e:#}").starts_with("creating the Vulkan device: vkCreateDevice failed"), "{e:#}");
        // Text that merely mentions an input problem does not make an error bad input.
        assert_eq!(exit_code(&anyhow::anyhow!("cannot read s.toml")), RUNTIME);
    }

    #[test]
    fn a_report_is_one_line() {
        let mut err = vec![];
        let e = anyhow::anyhow!("first\nsecond").context("outer");
        assert_eq!(report(&e, &mut err), RUNTIME);
        assert_eq!(String::from_utf8(err).unwrap(), "error: outer: first second\n");
    }

    #[test]
    fn a_cause_its_wrapper_already_prints_is_said_once() {
        let missing = || std::io::Error::new(std::io::ErrorKind::NotFound, "no such file");
        let scene = SceneError::Io { path: PathBuf::from("s.toml"), source: missing() };
        let mut err = vec![];
        assert_eq!(report(&anyhow::Error::new(scene).context("loading"), &mut err), BAD_INPUT);
        assert_eq!(String::from_utf8(err).unwrap(), "error: loading: cannot read s.toml: no such file\n");
        // A cause that differs from its wrapper's ending is kept.
        let mut err = vec![];
        report(&anyhow::Error::new(missing()).context("writing out.exr"), &mut err);
        assert_eq!(String::from_utf8(err).unwrap(), "error: writing out.exr: no such file\n");
        // Bad input shows its whole chain, each cause once.
        let mut err = vec![];
        let wrapped = SceneError::Io { path: PathBuf::from("t.exr"), source: missing() };
        assert_eq!(report(&bad(anyhow::Error::new(wrapped).context("reading t.exr")), &mut err), BAD_INPUT);
        assert_eq!(String::from_utf8(err).unwrap(), "error: reading t.exr: cannot read t.exr: no such file\n");
    }
}
