//! The `bounce` binary: `bounce::run` (`src/lib.rs`) on the process's arguments, stdout and stderr.

fn main() {
    let code = bounce::run(std::env::args_os().collect(), &mut std::io::stdout(), &mut std::io::stderr());
    std::process::exit(code);
}
