//! `petrinav` alone: what it is and the five commands to start with, on
//! standard output with exit code 0 (docs/commands.md), the same commands
//! as the README's tour.

use std::path::Path;
use std::process::Command;

fn petrinav(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_petrinav"))
        .args(args)
        .output()
        .expect("the petrinav binary runs")
}

/// The command lines `petrinav` alone lists (lines starting with
/// `petrinav `, up to two spaces before their comment).
fn listed_commands(text: &str) -> Vec<String> {
    text.lines()
        .map(str::trim_start)
        .filter(|l| l.starts_with("petrinav ") && !l.starts_with("petrinav --help"))
        .map(|l| l.split("  ").next().unwrap_or(l).trim().to_string())
        .collect()
}

#[test]
fn petrinav_alone_says_what_it_is_and_five_commands_with_exit_code_0() {
    let out = petrinav(&[]);
    assert!(out.status.success(), "exit code {:?}", out.status.code());
    assert!(out.stderr.is_empty(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.lines()
            .next()
            .unwrap()
            .starts_with("petrinav: a workbench for"),
        "{text}"
    );
    let commands = listed_commands(&text);
    assert_eq!(commands.len(), 5, "{commands:?}");
    assert!(text.contains("petrinav --help"), "{text}");
}

#[test]
fn the_five_commands_are_the_readmes_and_their_subcommands_exist() {
    let text = String::from_utf8(petrinav(&[]).stdout).unwrap();
    let readme =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../README.md")).unwrap();
    for command in listed_commands(&text) {
        assert!(
            readme.contains(&command),
            "the README's tour does not show `{command}`"
        );
        // The subcommand parses: its --help succeeds.
        let words: Vec<&str> = command.split_whitespace().skip(1).take(2).collect();
        let help = petrinav(&[words[0], words[1], "--help"]);
        assert!(
            help.status.success(),
            "`petrinav {} {} --help` failed",
            words[0],
            words[1]
        );
    }
}

#[test]
fn help_and_a_wrong_command_keep_clap_s_conventions() {
    let help = petrinav(&["--help"]);
    assert!(help.status.success());
    assert!(String::from_utf8_lossy(&help.stdout).contains("Commands:"));
    let wrong = petrinav(&["frobnicate"]);
    assert_eq!(wrong.status.code(), Some(2), "a usage error exits with 2");
}
