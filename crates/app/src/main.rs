//! The `bounce` binary: see the `bounce` library crate (`src/lib.rs`) for the commands.

fn main() {
    let code = bounce::run(std::env::args_os().collect(), &mut std::io::stdout(), &mut std::io::stderr());
    std::process::exit(code);
}
