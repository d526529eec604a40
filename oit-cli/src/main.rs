//! `oit`: the command line of oit. Everything is in the library (`oit_cli`), so that the fuzz
//! harness (`oit-fuzz`) reaches the same parsing and checks; see its docs for the contract.

fn main() -> std::process::ExitCode {
    oit_cli::main()
}
