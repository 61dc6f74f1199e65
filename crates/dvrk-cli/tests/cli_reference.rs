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

/// The subcommands a help text lists, without clap's own `help`: in clap's layout, the
/// lines indented by exactly two spaces whose first word is a lower-case name (options
/// start with `-`, arguments with `<` or `[`), under "Commands:" or under the headings
/// of grouped subcommands alike; none when the usage line names no `<COMMAND>`.
fn subcommands(text: &str) -> Vec<String> {
    let mut names = Vec::new();
    // Only a command with subcommands (`<COMMAND>` in its usage) lists any.
    let usage = text.lines().find(|l| l.starts_with("Usage:"));
    if !usage.is_some_and(|u| u.contains("COMMAND")) {
        return names;
    }
    for line in text.lines() {
        let Some(entry) = line.strip_prefix("  ") else {
            continue;
        };
        let name = entry.split_whitespace().next().unwrap_or_default();
        let is_name = name.starts_with(|c: char| c.is_ascii_lowercase())
            && name
                .chars()
                .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-');
        if !entry.starts_with(' ') && is_name && name != "help" {
            names.push(name.to_string());
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

#[test]
fn subcommands_are_found_under_any_heading() {
    let grouped = "Identify robot arms\n\nUsage: dvrk-ident [OPTIONS] <COMMAND>\n\n\
                   Models:\n  model      Summarize a robot model\n\n\
                   Identification:\n  fit        Identify the parameters\n  \
                   cable-fit  Fit a known-force polynomial\n  help       Print this message\n\n\
                   Options:\n      --quiet    No progress bars\n  -h, --help     Print help\n";
    assert_eq!(subcommands(grouped), ["model", "fit", "cable-fit"]);
    let leaf = "Identify\n\nUsage: dvrk-ident fit [OPTIONS] [LOG]...\n\n\
                Arguments:\n  [LOG]...  Training logs\n\nOptions:\n      --robot <ROBOT>  Robot\n";
    assert!(subcommands(leaf).is_empty());
}
