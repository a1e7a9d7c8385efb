//! The `bounce` command line as a binary of this package, so the integration tests can run it as a
//! separate process (`CARGO_BIN_EXE_bounce-cli`): `bounce view` needs its event loop on a main thread
//! and a display (Xvfb), which an in-process test thread cannot give it.

fn main() {
    let (mut out, mut err) = (std::io::stdout(), std::io::stderr());
    std::process::exit(bounce::run(std::env::args_os().collect(), &mut out, &mut err));
}
