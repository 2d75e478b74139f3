//! The command-line reference, from clap's `Command` of [`crate::cli::Cli`].

use super::markdown::{cell, GENERATED};
use clap::{Arg, ArgAction, Command, CommandFactory};

/// `reference/cli.md`: every subcommand with its usage, arguments and options.
pub fn page() -> String {
    let mut root = crate::cli::Cli::command();
    root.build();
    let mut out = format!("{GENERATED}\n\n# Command line\n\n");
    out.push_str(&format!(
        "{}\n\nEvery command takes the global options below; `ribbar help COMMAND` \
         and `ribbar COMMAND --help` print the same text.\n\n",
        root.get_about().map(|a| a.to_string()).unwrap_or_default()
    ));
    out.push_str("| command | what it does |\n|---|---|\n");
    for sub in visible(&root) {
        out.push_str(&format!(
            "| [`{}`](#ribbar-{}) | {} |\n",
            sub.get_name(),
            sub.get_name(),
            cell(&about(sub))
        ));
    }
    out.push_str("\n## Global options\n\n");
    let globals: Vec<&Arg> = root
        .get_arguments()
        .filter(|a| a.is_global_set() && !a.is_hide_set())
        .collect();
    out.push_str(&arg_table(&globals));
    for sub in visible(&root) {
        out.push_str(&subcommand_section(sub));
    }
    out
}

fn visible(cmd: &Command) -> impl Iterator<Item = &Command> {
    cmd.get_subcommands()
        .filter(|s| !s.is_hide_set() && s.get_name() != "help")
}

fn about(cmd: &Command) -> String {
    cmd.get_long_about()
        .or(cmd.get_about())
        .map(|a| a.to_string())
        .unwrap_or_default()
}

fn subcommand_section(sub: &Command) -> String {
    let name = sub.get_name();
    let usage = sub
        .clone()
        .bin_name(format!("ribbar {name}"))
        .render_usage()
        .to_string();
    let usage = usage.trim_start_matches("Usage: ");
    let mut out = format!(
        "\n## ribbar {name}\n\n{}\n\n```text\n{usage}\n```\n\n",
        about(sub)
    );
    let args: Vec<&Arg> = sub
        .get_arguments()
        .filter(|a| !a.is_hide_set() && !a.is_global_set())
        .filter(|a| !matches!(a.get_action(), ArgAction::Help | ArgAction::Version))
        .collect();
    if !args.is_empty() {
        out.push_str(&arg_table(&args));
    }
    out
}

fn arg_table(args: &[&Arg]) -> String {
    let mut out = String::from("| argument | default | meaning |\n|---|---|---|\n");
    for arg in args {
        out.push_str(&format!(
            "| {} | {} | {} |\n",
            cell(&arg_name(arg)),
            cell(&default(arg)),
            cell(&help(arg))
        ));
    }
    out
}

fn arg_name(arg: &Arg) -> String {
    let value = arg
        .get_value_names()
        .map(|names| {
            names
                .iter()
                .map(|n| n.to_string())
                .collect::<Vec<_>>()
                .join(" ")
        })
        .unwrap_or_else(|| arg.get_id().to_string().to_uppercase());
    let takes_value = matches!(arg.get_action(), ArgAction::Set | ArgAction::Append);
    if arg.is_positional() {
        return format!("`{value}`");
    }
    let mut flags = Vec::new();
    if let Some(short) = arg.get_short() {
        flags.push(format!("-{short}"));
    }
    if let Some(long) = arg.get_long() {
        flags.push(format!("--{long}"));
    }
    let flags = flags.join(", ");
    if takes_value {
        format!("`{flags} {value}`")
    } else {
        format!("`{flags}`")
    }
}

fn default(arg: &Arg) -> String {
    if matches!(arg.get_action(), ArgAction::SetTrue | ArgAction::SetFalse) {
        return "–".into();
    }
    let defaults: Vec<String> = arg
        .get_default_values()
        .iter()
        .map(|v| v.to_string_lossy().into_owned())
        .collect();
    if !defaults.is_empty() {
        return format!("`{}`", defaults.join(" "));
    }
    if arg.is_positional() && arg.is_required_set() {
        "required".into()
    } else if matches!(arg.get_action(), ArgAction::Append) {
        "none; repeatable".into()
    } else {
        "–".into()
    }
}

fn help(arg: &Arg) -> String {
    let mut text = arg
        .get_long_help()
        .or(arg.get_help())
        .map(|h| h.to_string())
        .unwrap_or_default();
    let choices: Vec<String> = arg
        .get_possible_values()
        .iter()
        .filter(|v| !v.is_hide_set())
        .map(|v| match v.get_help() {
            Some(h) => format!(
                "`{}`: {}",
                v.get_name(),
                h.to_string().trim_end_matches('.')
            ),
            None => format!("`{}`", v.get_name()),
        })
        .collect();
    let is_flag = matches!(arg.get_action(), ArgAction::SetTrue | ArgAction::SetFalse);
    if !choices.is_empty() && !is_flag {
        text.push_str(&format!(" One of: {}.", choices.join("; ")));
    }
    text
}
