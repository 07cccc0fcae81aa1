//! # truss-man: the manual pages of every truss-mc binary
//!
//! `truss man`, `mc-shard man`, `mc-merge man` and `truss-mc man` print, from the same clap
//! definitions as their `--help`, one roff page for the command and one for each of its
//! subcommands (`truss-solve(1)`, `mc-shard-run(1)`, …, nested ones too), one after the
//! other, so that every page the command's SUBCOMMANDS section names is there (clap's own
//! `help` subcommand is left out of the pages):
//! `man ./truss.1` shows them in turn. Help text is written for the terminal, where
//! `` `code` `` reads as code; roff would print the backticks, so they are left out.

use std::io::Write;

/// Writes the man pages of `cmd` (roff) to `out`: the command's, then each subcommand's,
/// depth first, each titled with its full name (`truss-mc-shard-run`).
pub fn pages(cmd: clap::Command, out: &mut dyn Write) -> std::io::Result<()> {
    let mut cmd = without_backticks(cmd);
    cmd.build();
    let name = cmd.get_name().to_string();
    page(&cmd, &name, out)
}

/// `cmd`'s page under `title`, then its subcommands' pages.
fn page(cmd: &clap::Command, title: &str, out: &mut dyn Write) -> std::io::Result<()> {
    // Through memory: a failed write is an error here, not a panic in the renderer.
    let mut roff = Vec::new();
    clap_mangen::Man::new(cmd.clone())
        .title(title)
        .render(&mut roff)?;
    out.write_all(&roff)?;
    for sub in cmd.get_subcommands() {
        // The name clap_mangen's SUBCOMMANDS section gives the page: the display name that
        // `build` set (`truss-mc-shard-run`).
        let name = sub
            .get_display_name()
            .map(str::to_string)
            .unwrap_or_else(|| format!("{title}-{}", sub.get_name()));
        page(sub, &name, out)?;
    }
    Ok(())
}

/// `cmd` with the backticks taken out of its own, its arguments' and its subcommands' help,
/// and without clap's `help` subcommand (a page per page would be noise: `man` is the help).
fn without_backticks(cmd: clap::Command) -> clap::Command {
    let plain = |s: &clap::builder::StyledStr| s.to_string().replace('`', "");
    let mut cmd = cmd.disable_help_subcommand(true);
    if let Some(about) = cmd.get_about().map(plain) {
        cmd = cmd.about(about);
    }
    if let Some(about) = cmd.get_long_about().map(plain) {
        cmd = cmd.long_about(about);
    }
    cmd = cmd.mut_args(|a| {
        let (help, long) = (a.get_help().map(plain), a.get_long_help().map(plain));
        let a = match help {
            Some(h) => a.help(h),
            None => a,
        };
        match long {
            Some(h) => a.long_help(h),
            None => a,
        }
    });
    cmd.mut_subcommands(without_backticks)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cli() -> clap::Command {
        clap::Command::new("tool")
            .about("The `tool` command.")
            .arg(clap::Arg::new("job").long("job").help("The `job` file"))
            .subcommand(
                clap::Command::new("run")
                    .about("Run `it`")
                    .subcommand(clap::Command::new("fast").about("Fast")),
            )
            .subcommand(clap::Command::new("merge").about("Merge"))
    }

    /// Every page a SUBCOMMANDS section names is rendered, nested ones too, and no backtick
    /// is left in the roff.
    #[test]
    fn every_named_page_is_there_without_backticks() {
        let mut out = Vec::new();
        pages(cli(), &mut out).unwrap();
        let roff = String::from_utf8(out).unwrap();
        let titles: Vec<&str> = roff
            .lines()
            .filter_map(|l| l.strip_prefix(".TH "))
            .map(|l| l.split(' ').next().unwrap())
            .collect();
        assert_eq!(
            titles,
            ["tool", "tool-run", "tool-run-fast", "tool-merge"],
            "{roff}"
        );
        // Each reference names a page rendered here.
        for l in roff.lines() {
            if let Some(r) = l.strip_suffix("(1)") {
                let r = r.replace("\\-", "-");
                assert!(titles.contains(&r.as_str()), "{r}(1) has no page:\n{roff}");
            }
        }
        assert!(!roff.contains('`'), "{roff}");
        assert!(roff.contains("tool \\- The tool command."), "{roff}");
    }
}
