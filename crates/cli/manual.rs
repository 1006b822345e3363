//! The help and the manual: `--help` wrapped to the terminal's width, and a roff manual page for
//! `urdf-dh` and for each of its commands (`urdf-dh man`).

use std::io::{IsTerminal, Write};
use std::path::Path;

use anyhow::Result;
use clap::{Args, CommandFactory};
use clap_mangen::roff::{roman, Roff};

use dh_workflows::error::hinted;
use dh_workflows::output::{check_destinations, write_all};
use dh_workflows::text::escape;

use crate::cli::Cli;
use crate::error::Outcome;

/// The widest `--help` in columns: a terminal's width up to this, and exactly this when standard
/// output is not a terminal (a pipe, a file, a test), so that what is written is the same
/// wherever it is written and whatever `COLUMNS` says.
pub const HELP_WIDTH: usize = 100;

/// `cmd` with its help wrapped as [`HELP_WIDTH`] says (the setting reaches every subcommand).
pub fn sized(cmd: clap::Command) -> clap::Command {
    if std::io::stdout().is_terminal() {
        cmd.max_term_width(HELP_WIDTH)
    } else {
        cmd.term_width(HELP_WIDTH)
    }
}

/// `urdf-dh man`: which manual pages to print or write.
#[derive(Debug, Args)]
pub struct ManCli {
    /// The command whose page to print, urdf-dh-COMMAND(1) [default: the top page, urdf-dh(1)].
    #[arg(value_name = "COMMAND")]
    pub command: Option<String>,
    /// Write every page (urdf-dh.1, urdf-dh-extract.1, ...) into this existing directory instead
    /// of printing one: all of them or, on any error, none.
    #[arg(long, value_name = "DIR", conflicts_with = "command")]
    pub dir: Option<String>,
}

/// One manual page.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Page {
    /// The page's name: `urdf-dh`, `urdf-dh-extract`, ...; its file is `NAME.1`.
    pub name: String,
    /// The page (roff, section 1).
    pub roff: Vec<u8>,
}

impl Page {
    /// The page's file name, `NAME.1`.
    pub fn file_name(&self) -> String {
        format!("{}.{SECTION}", self.name)
    }
}

/// The manual section of every page: user commands.
const SECTION: &str = "1";

/// Every manual page of `urdf-dh`: the top page first (whose SUBCOMMANDS section names the
/// others as `urdf-dh-COMMAND(1)`), then one per command, depth first, in the order of `--help`.
/// clap's `help` command has no page: `--help` is an option of every command.
///
/// # Errors
/// A page that cannot be rendered (clap_mangen's writer is an in-memory buffer here, so none
/// is expected).
pub fn pages() -> Result<Vec<Page>> {
    let mut top = Cli::command().disable_help_subcommand(true);
    // Building names every command for its page: the display name `urdf-dh-extract` and the
    // synopsis `urdf-dh extract`.
    top.build();
    let source = format!("urdf-dh {}", top.get_version().unwrap_or_default());
    let mut pages = Vec::new();
    collect(&top, &source, None, &mut pages)?;
    Ok(pages)
}

/// Renders `cmd`'s page and those of its commands into `pages`; `parent` is the page that
/// names it (its SEE ALSO).
fn collect(
    cmd: &clap::Command,
    source: &str,
    parent: Option<&str>,
    pages: &mut Vec<Page>,
) -> Result<()> {
    let name = cmd.get_display_name().unwrap_or(cmd.get_name()).to_owned();
    // The examples get a section of their own below, instead of clap_mangen's "EXTRA".
    let examples = cmd.get_after_help().map(|h| h.to_string());
    let man = clap_mangen::Man::new(cmd.clone().after_help(None::<&str>))
        .section(SECTION)
        .source(source);
    let mut roff = Vec::new();
    man.render(&mut roff)?;
    let mut more = Roff::new();
    if let Some(examples) = examples {
        more.control("SH", ["EXAMPLES"]);
        // Unfilled, as typed at a shell; each line one command.
        more.control("nf", []);
        let lines = examples.lines().filter(|l| l.trim_end() != "EXAMPLES:");
        for line in lines {
            more.text([roman(line.strip_prefix("  ").unwrap_or(line))]);
        }
        more.control("fi", []);
    }
    if let Some(parent) = parent {
        more.control("SH", ["SEE ALSO"]);
        more.text([roman(format!("{parent}({SECTION})"))]);
    }
    let more = more.render();
    // `render` starts with the apostrophe string's definition, which the page already has.
    let more = more.strip_prefix(APOSTROPHE_PREAMBLE).unwrap_or(&more);
    roff.extend_from_slice(more.as_bytes());
    pages.push(Page {
        name: name.clone(),
        roff,
    });
    for sub in cmd.get_subcommands().filter(|s| !s.is_hide_set()) {
        collect(sub, source, Some(&name), pages)?;
    }
    Ok(())
}

/// The lines with which `roff` starts a rendered document (roff 1.1: `\*(Aq` for apostrophes).
const APOSTROPHE_PREAMBLE: &str = ".ie \\n(.g .ds Aq \\(aq\n.el .ds Aq '\n";

/// Runs `urdf-dh man`: prints the top page or one command's page to `out`, or writes every page
/// into `--dir` by the rules of [`dh_workflows::output`] (all or none; a directory or a socket
/// where a page would go is refused before anything is written).
///
/// # Errors
/// An unknown command (exit 2, naming the commands that have a page), a directory that does not
/// exist or cannot be written, a failed write.
pub fn man(args: &ManCli, out: &mut dyn Write) -> Result<Outcome> {
    let pages = pages()?;
    if let Some(dir) = &args.dir {
        let paths: Vec<String> = pages
            .iter()
            .map(|p| {
                Path::new(dir)
                    .join(p.file_name())
                    .to_string_lossy()
                    .into_owned()
            })
            .collect();
        let outputs: Vec<(&str, &str)> = paths.iter().map(|p| ("--dir", p.as_str())).collect();
        check_destinations(&[], &outputs)?;
        let files: Vec<(&Path, &[u8])> = paths
            .iter()
            .zip(&pages)
            .map(|(path, page)| (Path::new(path), page.roff.as_slice()))
            .collect();
        write_all(&files)?;
        return Ok(Outcome::Pass);
    }
    let wanted = match &args.command {
        Some(command) => format!("urdf-dh-{command}"),
        None => "urdf-dh".to_owned(),
    };
    let Some(page) = pages.iter().find(|p| p.name == wanted) else {
        let commands: Vec<&str> = pages
            .iter()
            .filter_map(|p| p.name.strip_prefix("urdf-dh-"))
            .collect();
        return Err(hinted(
            format!(
                "man: expected a command of urdf-dh, found '{}'",
                escape(args.command.as_deref().unwrap_or_default())
            ),
            format!("the commands with a page: {}", commands.join(", ")),
        ));
    };
    out.write_all(&page.roff)?;
    Ok(Outcome::Pass)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_page_the_top_page_names_exists_and_names_it_back() {
        let pages = pages().unwrap();
        assert_eq!(pages[0].name, "urdf-dh");
        let top = String::from_utf8(pages[0].roff.clone()).unwrap();
        let named: Vec<String> = top
            .lines()
            .filter_map(|l| l.strip_suffix("(1)"))
            .map(|l| l.replace("\\-", "-"))
            .collect();
        assert!(named.len() >= 13, "{named:?}");
        for name in &named {
            let page = pages.iter().find(|p| &p.name == name);
            let page = page.unwrap_or_else(|| panic!("{name}(1) is named but has no page"));
            let text = String::from_utf8(page.roff.clone()).unwrap();
            assert!(
                text.contains("\n.SH \"SEE ALSO\"\nurdf\\-dh(1)\n"),
                "{text}"
            );
        }
        // No page that the top page does not name, and no `help` page.
        assert_eq!(named.len() + 1, pages.len());
        assert!(!named.iter().any(|n| n == "urdf-dh-help"));
    }

    #[test]
    fn a_command_page_has_its_options_and_its_examples_unfilled() {
        let pages = pages().unwrap();
        let page = pages.iter().find(|p| p.name == "urdf-dh-extract").unwrap();
        let text = String::from_utf8(page.roff.clone()).unwrap();
        assert!(text.starts_with(APOSTROPHE_PREAMBLE), "{text}");
        assert_eq!(text.matches(APOSTROPHE_PREAMBLE).count(), 1, "{text}");
        let version = env!("CARGO_PKG_VERSION");
        let title = format!(".TH urdf-dh-extract 1  \"urdf-dh {version}\"");
        assert!(text.contains(&title), "{text}");
        assert!(text.contains("\\fB\\-\\-convention\\fR"), "{text}");
        assert!(
            text.contains(".SH EXAMPLES\n.nf\nurdf\\-dh extract robot.urdf"),
            "{text}"
        );
        assert!(!text.contains(".SH EXTRA"), "{text}");
    }
}
