//! The tests' own helpers (tests/common): a wait for a line that does not come says which process
//! and which line, with what the process printed.

mod common;
use common::*;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::process::Command;

#[test]
fn a_line_that_never_comes_names_the_process_and_the_line() {
    let mut cmd = Command::new("sh");
    cmd.args(["-c", "echo hello"]);
    let proc = start(cmd);
    let panic = catch_unwind(AssertUnwindSafe(|| proc.stdout_line("never"))).unwrap_err();
    let said = panic.downcast_ref::<String>().expect("a formatted message");
    assert!(said.starts_with("`sh -c echo hello` (pid "), "{said}");
    assert!(
        said.ends_with("printed no line containing \"never\" before it closed its stdout; saw:\nhello"),
        "{said}"
    );
}
