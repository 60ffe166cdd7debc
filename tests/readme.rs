//! The README stays short (at most 250 lines) and names every capability with a link to its
//! document, and every document it links exists.

#[test]
fn the_readme_lists_every_capability_with_its_document_within_250_lines() {
    let text = std::fs::read_to_string("README.md").unwrap();
    let lines = text.lines().count();
    assert!(lines <= 250, "README.md has {lines} lines");
    for needle in [
        "docs/OPTICS.md",
        "docs/OPTIMAL.md",
        "docs/EYE.md",
        "docs/RESOLUTION.md",
        "docs/SWEEPS.md",
        "docs/PYTHON.md",
        "docs/CONFIGURATION.md#a-display-stated-by-intent",
        "Diffraction",
        "Real lenslets",
        "`[intent]`",
        "`info --write-display`",
    ] {
        assert!(text.contains(needle), "README.md does not mention {needle}");
    }
    // Every linked document exists, and so does every anchor's heading.
    for link in text.split("](").skip(1).filter_map(|t| t.split(')').next()) {
        let (path, anchor) = link.split_once('#').map_or((link, None), |(p, a)| (p, Some(a)));
        if path.starts_with("http") || path.is_empty() {
            continue;
        }
        assert!(std::path::Path::new(path).exists(), "README links {path}, which does not exist");
        if let Some(anchor) = anchor {
            let doc = std::fs::read_to_string(path).unwrap();
            let found = doc.lines().filter(|l| l.starts_with('#')).any(|h| {
                let slug: String = h
                    .trim_start_matches('#')
                    .trim()
                    .to_lowercase()
                    .chars()
                    .filter(|c| c.is_alphanumeric() || *c == ' ' || *c == '-')
                    .map(|c| if c == ' ' { '-' } else { c })
                    .collect();
                slug == anchor
            });
            assert!(found, "README links {path}#{anchor}: no such heading");
        }
    }
}
