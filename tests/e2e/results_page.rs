//! docs/results.md as committed (`sil-host report --results docs/results.md`): every
//! image it shows is in the repository, beside it under docs/figures/, referenced by
//! relative path; it names no temporary folder and no absolute path; docs/figures/
//! holds nothing it does not show; its figures are numbered in order, each with a
//! caption. Reads the committed page only (fast: it does not run the report).

use std::{
    collections::BTreeSet,
    path::{Path, PathBuf},
};

fn docs() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs")
}

fn page() -> String {
    std::fs::read_to_string(docs().join("results.md")).expect("docs/results.md")
}

/// The targets of the page's `![alt](target)`.
fn images(page: &str) -> Vec<String> {
    page.split("![")
        .skip(1)
        .filter_map(|s| s.split_once("](").and_then(|(_, rest)| rest.split_once(')')).map(|(t, _)| t.to_string()))
        .collect()
}

#[test]
fn every_image_of_the_results_page_is_in_the_repository() {
    let page = page();
    let images = images(&page);
    assert!(images.len() >= 10, "{} images on docs/results.md", images.len());
    for target in &images {
        // The figures (SVG, their PDFs beside them) and the report's animations (GIF).
        assert!(
            target.starts_with("figures/") && (target.ends_with(".svg") || target.ends_with("/animation.gif")),
            "{target}: not a relative path to an SVG or a report animation in docs/figures/"
        );
        assert!(docs().join(target).is_file(), "{target} is referenced by docs/results.md but not in docs/");
    }
}

#[test]
fn docs_figures_holds_only_what_the_page_shows() {
    let shown: BTreeSet<PathBuf> = images(&page()).iter().map(|t| docs().join(t)).collect();
    let mut stack = vec![docs().join("figures")];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else {
                assert!(shown.contains(&path), "{} is in docs/figures/ but docs/results.md does not show it", path.display());
            }
        }
    }
}

#[test]
fn the_results_page_names_no_temporary_folder_nor_absolute_path() {
    let page = page();
    assert!(!page.contains("/tmp"), "docs/results.md names /tmp");
    // A word that starts with `/` and a letter is an absolute path (`/home/..`, `/work/..`).
    for word in page.split(|c: char| c.is_whitespace() || "`()[]\"',;=".contains(c)) {
        let mut chars = word.chars();
        let absolute = chars.next() == Some('/') && chars.next().is_some_and(|c| c.is_ascii_alphabetic());
        assert!(!absolute, "docs/results.md names an absolute path: {word}");
    }
}

#[test]
fn the_results_page_numbers_its_figures_in_order_each_with_a_caption() {
    let page = page();
    let captions: Vec<usize> = page
        .lines()
        .filter_map(|l| l.strip_prefix("**Figure ").and_then(|rest| rest.split_once(".**")).and_then(|(n, _)| n.parse().ok()))
        .collect();
    assert!(!captions.is_empty(), "no numbered figure");
    assert_eq!(captions, (1..=captions.len()).collect::<Vec<_>>(), "figures numbered 1, 2, ... in the page's order");
    // Each caption says whether the paper has a counterpart.
    for l in page.lines().filter(|l| l.starts_with("**Figure ")) {
        assert!(l.contains("In the paper: ") || l.contains("No counterpart in the paper."), "{l}");
    }
    // Each image belongs to the figure whose caption follows it.
    let mut next = 1;
    for l in page.lines() {
        if let Some(i) = l.find("![Figure ") {
            let n: usize = l[i + 9..].split([':', ',']).next().unwrap().parse().unwrap();
            assert_eq!(n, next, "{l}");
        } else if l.starts_with(&format!("**Figure {next}.**")) {
            next += 1;
        }
    }
}
