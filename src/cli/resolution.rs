//! `inimtrace resolution`: the perceived-resolution study (the library's `resolution::command`),
//! or `--check` of its inputs without running it.

use std::path::PathBuf;

use anyhow::Result;

use inimtrace::resolution::command::{self as resolution, ResolutionCommand};

use crate::Globals;

/// `inimtrace resolution`: loads the study (default: the built-in studies/paper.toml), warns of
/// likely unit mistakes, then checks it (`check`) or runs it into `out`; prints its own timings.
pub(crate) fn resolution(
    g: &Globals,
    study: Option<PathBuf>,
    out: Option<PathBuf>,
    force: bool,
    check: bool,
) -> Result<()> {
    let cmd = ResolutionCommand { study, out, overrides: g.set.clone(), quiet: g.quiet, force };
    // Likely unit mistakes before the run (which may take minutes), not after it.
    let study = resolution::load_study(&cmd)?;
    for w in resolution::plausibility_warnings(&study) {
        eprintln!("warning: {w}");
    }
    if check {
        outln!("{}", resolution::check_text(&study)?);
        return Ok(());
    }
    let run = resolution::execute(&cmd)?;
    if !g.quiet {
        eprint!("{}", run.timings_text());
        eprintln!("wrote {}", run.out.display());
    }
    Ok(())
}
