//! `dvrk-ident completions SHELL` and `dvrk-ident man [COMMAND] [--out DIR]`: the shell
//! completion scripts and the manual pages, both generated from the command line's own
//! definition (clap_complete, clap_mangen), so they list exactly its subcommands and
//! flags.

use std::path::Path;

use anyhow::{bail, Result};
use clap_complete::Shell;
use dvrk_logs::output::Outputs;

use super::args::OUTPUT;
use super::emit;

/// How to install each script, shown by `completions --help`.
const INSTALL: &str = "\
Install (the folders are each shell's usual ones; open a new shell afterwards):
  bash:        dvrk-ident completions bash > ~/.local/share/bash-completion/completions/dvrk-ident
  zsh:         dvrk-ident completions zsh > ~/.zfunc/_dvrk-ident
               (with `fpath+=~/.zfunc; autoload -Uz compinit; compinit` in ~/.zshrc)
  fish:        dvrk-ident completions fish > ~/.config/fish/completions/dvrk-ident.fish
  powershell:  dvrk-ident completions powershell | Out-String | Invoke-Expression
               (in $PROFILE)
  elvish:      dvrk-ident completions elvish >> ~/.config/elvish/rc.elv
Packagers: generate the script at build time into the shell's system folder
(/usr/share/bash-completion/completions/dvrk-ident,
/usr/share/zsh/site-functions/_dvrk-ident,
/usr/share/fish/vendor_completions.d/dvrk-ident.fish).";

#[derive(clap::Args)]
#[command(after_help = INSTALL)]
pub struct CompletionsArgs {
    /// The shell to complete for
    #[arg(value_enum)]
    pub shell: Shell,
}

/// Prints the completion script of `cli` (the whole command line) for the shell.
pub fn completions(args: CompletionsArgs, mut cli: clap::Command) -> Result<()> {
    let mut script = Vec::new();
    clap_complete::generate(args.shell, &mut cli, "dvrk-ident", &mut script);
    emit(&String::from_utf8(script)?)
}

/// How the pages are read and installed, shown by `man --help`.
const PAGES: &str = "\
Read a page: dvrk-ident man fit | man -l -
Install: dvrk-ident man --out ~/.local/share/man/man1 (then `man dvrk-ident-fit`);
packagers: dvrk-ident man --out <staging>/usr/share/man/man1 (and gzip the pages if
the distribution does).";

#[derive(clap::Args)]
#[command(after_help = PAGES)]
pub struct ManArgs {
    /// The subcommand whose page is printed (e.g. fit) [default: the main page,
    /// dvrk-ident(1)]
    #[arg(value_name = "COMMAND", conflicts_with = "out")]
    pub command: Option<String>,
    /// Write every page into this folder instead of printing one: dvrk-ident.1 and
    /// dvrk-ident-<command>.1 for each subcommand (all of them or none; the folder is
    /// created if missing, not its parent)
    #[arg(long, value_name = "DIR", help_heading = OUTPUT)]
    pub out: Option<String>,
}

/// The pages of `cli`: `(file name, roff text)`, the main page first, then one per
/// subcommand in the order of the help.
fn pages(cli: clap::Command) -> Result<Vec<(String, Vec<u8>)>> {
    let mut cli = cli.disable_help_subcommand(true);
    cli.build();
    let mut out = Vec::new();
    let mut cmds = vec![cli.clone()];
    cmds.extend(cli.get_subcommands().filter(|s| !s.is_hide_set()).cloned());
    for cmd in cmds {
        let man = clap_mangen::Man::new(cmd);
        let mut text = Vec::new();
        man.render(&mut text)?;
        out.push((man.get_filename(), text));
    }
    Ok(out)
}

/// Prints one manual page, or writes them all into a folder.
pub fn man(args: ManArgs, cli: clap::Command) -> Result<()> {
    let subcommands: Vec<String> = cli
        .get_subcommands()
        .filter(|s| !s.is_hide_set())
        .map(|s| s.get_name().to_string())
        .collect();
    if let Some(dir) = &args.out {
        super::check_outputs(&[], &[("--out", Some(dir))], &Default::default())?;
        let pages = pages(cli)?;
        let files: Vec<(String, &[u8])> = pages
            .iter()
            .map(|(name, text)| (name.clone(), text.as_slice()))
            .collect();
        let mut outputs = Outputs::new();
        let written = outputs.add_dir(Path::new(dir), &files)?;
        outputs.commit()?;
        let names: Vec<String> = written.iter().map(|p| p.display().to_string()).collect();
        return emit(&names.join("\n"));
    }
    let wanted = match &args.command {
        None => "dvrk-ident.1".to_string(),
        Some(c) if subcommands.contains(c) => format!("dvrk-ident-{c}.1"),
        Some(c) => bail!(
            "man {c}: no such subcommand; the pages are of {}",
            subcommands.join(", ")
        ),
    };
    let pages = pages(cli)?;
    let (_, text) = pages
        .into_iter()
        .find(|(name, _)| *name == wanted)
        .ok_or_else(|| anyhow::anyhow!("no manual page {wanted}"))?;
    emit(&String::from_utf8(text)?)
}
