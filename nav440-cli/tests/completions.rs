//! `nav440 completions SHELL`: the scripts complete the documented commands and options.
//!
//! Bash is run for real (the script is sourced and its completion function called the way
//! bash calls it on TAB); zsh and fish are not installed on the CI machine, so their scripts
//! are checked for their headers and for every command of docs/CLI.md.

use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_nav440");

/// Every subcommand named in docs/CLI.md and docs/UNIT.md.
const COMMANDS: &[&str] = &[
    "stats",
    "decode",
    "estimate",
    "paper",
    "tune",
    "plot",
    "synth",
    "sim",
    "config",
    "record",
    "live",
    "rows",
    "completions",
];

fn nav440(args: &[&str]) -> Output {
    Command::new(BIN).args(args).output().expect("run nav440")
}

fn script(shell: &str) -> String {
    let out = nav440(&["completions", shell]);
    assert!(out.status.success(), "{shell}: {out:?}");
    assert!(out.stderr.is_empty(), "{shell}: stderr {:?}", out.stderr);
    String::from_utf8(out.stdout).expect("UTF-8 script")
}

/// Sources the bash script and returns what TAB completes for `words` (the last one is the
/// word being completed), one candidate per line.
fn bash_complete(words: &[&str]) -> Vec<String> {
    let path = std::env::temp_dir().join(format!("nav440-completion-{}.bash", std::process::id()));
    std::fs::write(&path, script("bash")).expect("write script");
    let quoted: Vec<String> = words.iter().map(|w| format!("'{w}'")).collect();
    let program = format!(
        "source '{}'\nCOMP_WORDS=({})\nCOMP_CWORD={}\nCOMP_LINE='{}'\nCOMP_POINT=${{#COMP_LINE}}\n\
         _nav440 nav440 '{}' '{}'\nprintf '%s\\n' \"${{COMPREPLY[@]}}\"\n",
        path.display(),
        quoted.join(" "),
        words.len() - 1,
        words.join(" "),
        words[words.len() - 1],
        words[words.len() - 2],
    );
    let out = Command::new("bash")
        .args(["--norc", "--noprofile", "-c", &program])
        .output()
        .expect("run bash");
    let _ = std::fs::remove_file(&path);
    assert!(out.status.success(), "bash failed: {out:?}");
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| l.trim().to_owned())
        .filter(|l| !l.is_empty())
        .collect()
}

#[test]
fn bash_completes_commands_and_options() {
    let s = script("bash");
    let syntax = Command::new("bash")
        .args(["-n", "-c", &s])
        .output()
        .expect("run bash -n");
    assert!(syntax.status.success(), "bash -n: {syntax:?}");
    assert!(s.contains("complete -F _nav440"), "registers the function");

    let all = bash_complete(&["nav440", ""]);
    for c in COMMANDS {
        assert!(all.iter().any(|w| w == c), "{c} missing in {all:?}");
    }
    assert_eq!(bash_complete(&["nav440", "est"]), ["estimate"]);
    let opts = bash_complete(&["nav440", "estimate", "--ho"]);
    assert_eq!(opts, ["--hold"]);
    let shells = bash_complete(&["nav440", "completions", ""]);
    for sh in ["bash", "zsh", "fish"] {
        assert!(shells.iter().any(|w| w == sh), "{sh} missing in {shells:?}");
    }
}

#[test]
fn zsh_and_fish_scripts_name_every_command() {
    let zsh = script("zsh");
    assert!(zsh.starts_with("#compdef nav440"), "{}", &zsh[..40]);
    let fish = script("fish");
    assert!(fish.contains("complete -c nav440"));
    for c in COMMANDS {
        assert!(zsh.contains(&format!("'{c}:")), "zsh: {c}");
        assert!(fish.contains(&format!("-a \"{c}\"")), "fish: {c}");
    }
}

#[test]
fn unknown_shell_is_a_usage_error() {
    let out = nav440(&["completions", "tcsh"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.starts_with("nav440: invalid value 'tcsh'"), "{err}");
    assert_eq!(err.lines().count(), 1, "one line: {err}");
    assert!(out.stdout.is_empty());
}
