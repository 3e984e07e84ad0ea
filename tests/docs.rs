//! The documentation a new user reads is self-contained and agrees with the binary: every
//! relative link of the README and docs/ resolves inside the repository, no file cites a
//! document that is not in it, the README's lists of `--env` values and audit exit statuses
//! are the ones the command line has, and the README explains what a guarantee means.
//!
//! Cost: reads the repository's text files once and runs `--help` twice (well under a second).

use std::path::{Path, PathBuf};

use crate::common::sepg;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// The README and every markdown file of docs/.
fn markdown_files() -> Vec<PathBuf> {
    let mut files = vec![root().join("README.md")];
    let docs = std::fs::read_dir(root().join("docs")).expect("docs/");
    for entry in docs {
        let p = entry.expect("entry").path();
        if p.extension().is_some_and(|e| e == "md") {
            files.push(p);
        }
    }
    files.sort();
    files
}

/// The targets of the markdown links `[text](target)` of `text`.
fn links(text: &str) -> Vec<&str> {
    text.match_indices("](")
        .filter_map(|(i, _)| {
            let rest = &text[i + 2..];
            rest.find(')').map(|end| &rest[..end])
        })
        .collect()
}

#[test]
fn every_relative_link_resolves_inside_the_repository() {
    let mut checked = 0;
    for file in markdown_files() {
        let text = read(&file);
        let dir = file.parent().expect("parent");
        for target in links(&text) {
            if target.contains("://") || target.starts_with('#') || target.starts_with("mailto:") {
                continue;
            }
            let path = target.split('#').next().unwrap_or(target);
            let resolved = dir.join(path);
            assert!(
                resolved.exists(),
                "{}: link {target} points to nothing",
                file.display()
            );
            let inside = resolved
                .canonicalize()
                .is_ok_and(|p| p.starts_with(root().canonicalize().expect("root")));
            assert!(
                inside,
                "{}: link {target} leaves the repository",
                file.display()
            );
            checked += 1;
        }
    }
    // The README alone links a dozen documents; an empty scan would mean the parser broke.
    assert!(checked > 20, "only {checked} links found");
}

/// Text files of the repository outside build output and version control.
fn text_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("read_dir") {
        let p = entry.expect("entry").path();
        let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
        if p.is_dir() {
            if !name.starts_with('.') && !["target", "node_modules", "__pycache__"].contains(&name)
            {
                text_files(&p, out);
            }
        } else if ["rs", "md", "toml", "py", "pyi", "sh", "sbatch", "txt"]
            .iter()
            .any(|e| p.extension().is_some_and(|x| x == *e))
        {
            out.push(p);
        }
    }
}

#[test]
fn no_file_cites_a_document_outside_the_repository() {
    let mut files = Vec::new();
    text_files(root(), &mut files);
    assert!(files.len() > 100, "only {} files found", files.len());
    // Built from pieces so that this file does not cite them itself.
    let forbidden = [
        ["SP", "EC §"].concat(),
        ["SP", "EC.md"].concat(),
        ["../", "shared"].concat(),
        ["sepg-thesis", ".txt"].concat(),
    ];
    for file in files {
        let Ok(text) = std::fs::read_to_string(&file) else {
            continue;
        };
        for f in &forbidden {
            assert!(
                !text.contains(f.as_str()),
                "{} cites {f:?}, which is not in the repository",
                file.display()
            );
        }
    }
}

/// The cell of column `col` of each row of the first markdown table of `text` after the
/// line starting with `after` whose header's first cell is `first`.
fn table_cells<'a>(text: &'a str, after: &str, first: &str, col: usize) -> Vec<&'a str> {
    let start = text.find(after).unwrap_or_else(|| panic!("no {after:?}"));
    text[start..]
        .lines()
        .skip_while(|l| !l.starts_with(&format!("| {first} |")))
        .skip(2)
        .take_while(|l| l.starts_with('|'))
        .map(|row| row.split('|').nth(col + 1).expect("cell").trim())
        .collect()
}

#[test]
fn the_readme_lists_the_env_values_the_command_line_accepts() {
    let readme = read(&root().join("README.md"));
    let row = table_cells(&readme, "### One run: `sepg run`", "option", 0)
        .iter()
        .position(|c| *c == "`env`")
        .expect("env row");
    let values = table_cells(&readme, "### One run: `sepg run`", "option", 1)[row];
    let listed: Vec<&str> = values
        .split(',')
        .map(|v| v.trim().trim_matches('`'))
        .collect();
    let help = String::from_utf8(sepg(&["run", "--help"]).stdout).expect("utf-8");
    let env_help = &help[help.find("--env <ENV>").expect("--env")..];
    let env_help = &env_help[..env_help.find("--features").expect("next flag")];
    let accepted: Vec<&str> = env_help
        .lines()
        .filter_map(|l| l.trim().strip_prefix("- "))
        .filter_map(|l| l.split(':').next())
        .collect();
    assert_eq!(listed, accepted);
}

#[test]
fn the_readme_documents_the_audit_exit_statuses_as_the_help_does() {
    let readme = read(&root().join("README.md"));
    let codes = table_cells(&readme, "### Auditing a run", "exit status", 0);
    let meanings = table_cells(&readme, "### Auditing a run", "exit status", 1);
    assert_eq!(codes, ["0", "1", "2"]);
    let help = String::from_utf8(sepg(&["audit", "--help"]).stdout).expect("utf-8");
    for (code, meaning) in codes.iter().zip(&meanings) {
        // The help states the same meaning; the README may list more of the malformed cases.
        let head = meaning.split(':').next().expect("meaning");
        assert!(
            help.contains(&format!("  {code}  {head}")),
            "exit {code}: {head:?} not in the help:\n{help}"
        );
    }
}

#[test]
fn the_readme_says_what_a_guarantee_means() {
    let readme = read(&root().join("README.md"));
    let start = readme
        .find("## What a guarantee means")
        .expect("the section");
    let section = &readme[start..];
    let section = &section[..section[3..].find("\n## ").map_or(section.len(), |e| e + 3)];
    for needed in [
        "| MI |",
        "| LB-I |",
        "| LB-II |",
        "| ZV |",
        "For the whole run",
        "1 − δ",
        "`proven`",
        "`approximate`",
        "under-cover",
        "N = 100",
        "R_max",
        "M_φ",
        "|A|",
        "docs/ERRATA.md",
    ] {
        assert!(
            section.contains(needed),
            "{needed:?} missing from the section"
        );
    }
    assert!(readme.contains("(docs/RELIABILITY.md)"));
}

/// The licences the manifests declare ("MIT OR Apache-2.0") are in the repository, with a
/// citation file for the software and the thesis it implements, and no manifest names a
/// placeholder repository URL.
#[test]
fn the_repository_carries_its_licences_and_citation() {
    let manifest = read(&root().join("Cargo.toml"));
    assert!(manifest.contains("license = \"MIT OR Apache-2.0\""));
    let mit = read(&root().join("LICENSE-MIT"));
    assert!(mit.starts_with("MIT License") && mit.contains("Permission is hereby granted"));
    let apache = read(&root().join("LICENSE-APACHE"));
    assert!(apache.contains("Apache License") && apache.contains("Version 2.0, January 2004"));
    let cff = read(&root().join("CITATION.cff"));
    assert!(cff.contains("cff-version: 1.2.0"), "{cff}");
    assert!(cff.contains("Balancing Safety and Exploration in Policy Gradient"));
    assert!(cff.contains("Politecnico di Milano") && cff.contains("type: thesis"));
    let mut manifests = vec![root().join("Cargo.toml")];
    for dir in ["crates", "."] {
        for entry in std::fs::read_dir(root().join(dir)).expect("read_dir") {
            let path = entry.expect("entry").path().join("Cargo.toml");
            if path.is_file() {
                manifests.push(path);
            }
        }
    }
    assert!(manifests.len() >= 9, "{manifests:?}");
    for m in manifests {
        assert!(!read(&m).contains("example.invalid"), "{}", m.display());
    }
}

/// The README says how to put the binary on the PATH, and its budget example says what
/// `sepg bounds` does with `--required` (each update's requirement, split only with `--nu`).
#[test]
fn the_readme_installs_the_binary_and_states_the_budget_split() {
    let readme = read(&root().join("README.md"));
    assert!(readme.contains("cargo install --path ."));
    assert!(
        readme.contains("without `--nu`"),
        "the budget example must name --nu"
    );
    assert!(readme.contains("`--required -0.5 --nu 0.5` gives −0.25 to each update"));
}
