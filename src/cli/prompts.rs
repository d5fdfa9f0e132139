//! `coherent prompts export DIR`: the built-in prompt templates as files, to edit and
//! pass back with `--prompts DIR` (docs/prompts.md lists each template's placeholders).

use std::path::PathBuf;

use clap::{Args, Subcommand};

use crate::session::{Error, prompts as session_prompts};

#[derive(Args)]
pub(crate) struct PromptsArgs {
    #[command(subcommand)]
    command: PromptsCommand,
}

#[derive(Subcommand)]
enum PromptsCommand {
    /// Write every built-in template into DIR (made when missing), one file each.
    Export {
        dir: PathBuf,
        /// Overwrite templates already in DIR.
        #[arg(long)]
        force: bool,
    },
}

pub(crate) fn prompts(args: &PromptsArgs) -> Result<u8, Error> {
    match &args.command {
        PromptsCommand::Export { dir, force } => {
            let written = session_prompts::export(dir, *force)?;
            println!(
                "wrote {} templates to {}; edit them and pass --prompts {} to run or bench",
                written.len(),
                dir.display(),
                dir.display()
            );
            Ok(0)
        }
    }
}
