//! The book's command-line reference (`docs/book/src/cli.md`) is the binary's own
//! `--help`, of the command and of every subcommand, rendered into Markdown: this test
//! renders it from the built binary and compares it with the committed file, so the
//! reference cannot drift from the command line. After a change of the command line,
//! one command rewrites the file:
//!
//! ```text
//! UPDATE_DOCS=1 cargo test --release -p dvrk-cli --test cli_reference
//! ```

use std::path::PathBuf;
use std::process::Command;

const REGENERATE: &str = "UPDATE_DOCS=1 cargo test --release -p dvrk-cli --test cli_reference";

fn reference_path() -> PathBuf {
    let crate_dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let repo = crate_dir
        .ancestors()
        .nth(2)
        .expect("crates/dvrk-cli is two levels down");
    repo.join("docs/book/src/cli.md")
}

/// `dvrk-ident <path...> --help`, as a user's terminal would not change it: a fixed
/// width for clap's wrapping (when enabled) and no colours.
fn help(path: &[String]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_dvrk-ident"))
        .args(path)
        .arg("--help")
        .env("COLUMNS", "100")
        .env("LINES", "50")
        .env("NO_COLOR", "1")
        .env_remove("CLICOLOR_FORCE")
        .output()
        .expect("runs the dvrk-ident binary");
    assert!(
        out.status.success(),
        "dvrk-ident {} --help failed: {}",
        path.join(" "),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("--help prints UTF-8")
}

/// The subcommands listed in the "Commands:" section of a help text (clap's layout: the
/// header, then one indented `name  description` line each, up to a blank line), without
/// clap's own `help`.
fn subcommands(text: &str) -> Vec<String> {
    let mut names = Vec::new();
    let mut inside = false;
    for line in text.lines() {
        if line == "Commands:" {
            inside = true;
        } else if inside && line.trim().is_empty() {
            break;
        } else if inside && line.starts_with("  ") && !line.starts_with("   ") {
            let name = line.split_whitespace().next().unwrap_or_default();
            if name != "help" {
                names.push(name.to_string());
            }
        }
    }
    names
}

/// Every command path, depth first in the order the help lists them: `[]` (the command
/// itself), `["model"]`, `["fit"]`, ..., with their help texts.
fn commands(path: Vec<String>, out: &mut Vec<(Vec<String>, String)>) {
    let text = help(&path);
    let children = subcommands(&text);
    out.push((path.clone(), text));
    for child in children {
        let mut p = path.clone();
        p.push(child);
        commands(p, out);
    }
}

fn render() -> String {
    let mut all = Vec::new();
    commands(Vec::new(), &mut all);
    let mut md = String::new();
    md.push_str("# Command-line reference\n\n");
    md.push_str(&format!(
        "<!-- Generated from the binary by crates/dvrk-cli/tests/cli_reference.rs: do not \
         edit. Regenerate with `{REGENERATE}`. -->\n\n"
    ));
    md.push_str(
        "The `--help` of `dvrk-ident` and of each of its subcommands, as the binary prints \
         them. This page is generated from the binary and compared with it by a test, so it \
         is the command line of this version. The chapters of the guide explain what the \
         options do and when to use them.\n\n",
    );
    for (path, _) in &all {
        if !path.is_empty() {
            let name = path.join(" ");
            md.push_str(&format!(
                "- [`dvrk-ident {name}`](#dvrk-ident-{})\n",
                path.join("-")
            ));
        }
    }
    for (path, text) in &all {
        let name = std::iter::once("dvrk-ident")
            .chain(path.iter().map(String::as_str))
            .collect::<Vec<_>>()
            .join(" ");
        md.push_str(&format!(
            "\n## `{name}`\n\n```text\n{}\n```\n",
            text.trim_end()
        ));
    }
    md
}

#[test]
fn the_book_s_command_line_reference_is_the_binary_s_help() {
    let rendered = render();
    assert!(
        rendered.contains("\n## `dvrk-ident fit`\n"),
        "no `fit` subcommand found in `dvrk-ident --help`:\n{rendered}"
    );
    let path = reference_path();
    if std::env::var_os("UPDATE_DOCS").is_some() {
        std::fs::write(&path, &rendered).expect("writes docs/book/src/cli.md");
        eprintln!("rewrote {}", path.display());
        return;
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    if committed != rendered {
        let (want, got): (Vec<&str>, Vec<&str>) = (
            rendered.split('\n').collect(),
            committed.split('\n').collect(),
        );
        let line = (0..want.len().max(got.len()))
            .find(|&i| want.get(i) != got.get(i))
            .unwrap_or(0);
        panic!(
            "{} is not the binary's --help (first difference at line {}: the binary gives \
             {:?}, the file has {:?}); regenerate it with\n    {REGENERATE}",
            path.display(),
            line + 1,
            want.get(line).copied().unwrap_or("(end of text)"),
            got.get(line).copied().unwrap_or("(end of file)"),
        );
    }
}
