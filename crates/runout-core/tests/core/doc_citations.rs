//! Every `methods.md §N[.M]` citation in the sources and docs resolves to a section of
//! `docs/methods.md` (the copy of the specification kept in the repository).

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Section numbers of `docs/methods.md`: "## 4. …" gives "4", "### 4.2 …" gives "4.2".
fn sections(methods: &str) -> BTreeSet<String> {
    methods
        .lines()
        .filter(|l| l.starts_with("## ") || l.starts_with("### "))
        .filter_map(|l| {
            let number = l.trim_start_matches('#').split_whitespace().next()?;
            let number = number.trim_end_matches('.');
            number
                .chars()
                .all(|c| c.is_ascii_digit() || c == '.')
                .then(|| number.to_string())
        })
        .collect()
}

fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap().flatten() {
        let path = entry.path();
        let name = entry.file_name();
        if name == "target" || name.to_string_lossy().starts_with('.') {
            continue;
        }
        if path.is_dir() {
            files(&path, out);
        } else if matches!(
            path.extension().and_then(|e| e.to_str()),
            Some("rs" | "md" | "toml")
        ) {
            out.push(path);
        }
    }
}

/// The section numbers cited as `methods.md §N.M` in `text`.
fn citations(text: &str) -> Vec<String> {
    let mut found = Vec::new();
    for (at, _) in text.match_indices("methods.md") {
        let rest = text[at + "methods.md".len()..].trim_start_matches(['`', ' ', ',']);
        let Some(rest) = rest.strip_prefix('§') else {
            continue;
        };
        let number: String = rest
            .chars()
            .take_while(|c| c.is_ascii_digit() || *c == '.')
            .collect();
        let number = number.trim_end_matches('.');
        if !number.is_empty() {
            found.push(number.to_string());
        }
    }
    found
}

#[test]
fn every_methods_citation_resolves_to_a_section() {
    let root = workspace_root();
    let methods = std::fs::read_to_string(root.join("docs/methods.md")).expect("docs/methods.md");
    let known = sections(&methods);
    assert!(
        known.contains("4.2") && known.contains("7"),
        "sections parsed: {known:?}"
    );
    let mut paths = Vec::new();
    for dir in ["crates", "docs", "fuzz"] {
        files(&root.join(dir), &mut paths);
    }
    paths.push(root.join("README.md"));
    let mut cited = 0;
    let mut unresolved = Vec::new();
    for path in paths {
        let Ok(text) = std::fs::read_to_string(&path) else {
            continue;
        };
        for number in citations(&text) {
            cited += 1;
            if !known.contains(&number) {
                unresolved.push(format!("{}: §{number}", path.display()));
            }
        }
    }
    assert!(
        cited > 100,
        "only {cited} citations found: is the scan broken?"
    );
    assert!(
        unresolved.is_empty(),
        "citations without a section in docs/methods.md: {unresolved:#?}"
    );
}

#[test]
fn no_citation_points_outside_the_repository() {
    let root = workspace_root();
    let mut paths = Vec::new();
    for dir in ["crates", "docs"] {
        files(&root.join(dir), &mut paths);
    }
    paths.push(root.join("README.md"));
    let outside: Vec<String> = paths
        .iter()
        .filter(|p| {
            std::fs::read_to_string(p)
                .is_ok_and(|t| t.contains("shared/spec/") && !p.ends_with("doc_citations.rs"))
        })
        .map(|p| p.display().to_string())
        .collect();
    assert!(
        outside.is_empty(),
        "files citing the spec outside the repository: {outside:#?}"
    );
}
