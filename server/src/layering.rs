//! The modules' layering, checked on the sources: data flows one way, `geometry` ← `collision` ←
//! `sliding`, `grasping` ← `scene` ← `simulation` ← `runtime` ← `replay`, `report`, so the
//! non-test code of a module names no module of its own layer or above (`sliding` and `grasping`
//! stay apart too, as do `replay` and `report`). Every `crate::` path counts, not only `use`
//! lines; code under `#[cfg(test)]` may reach up for its fixtures. The library names no client
//! crate: recordings are read by the binary alone.

use std::path::{Path, PathBuf};

/// The library's modules and their layers, lowest first.
const LAYERS: [(&str, u8); 9] = [
    ("geometry", 0),
    ("collision", 1),
    ("sliding", 2),
    ("grasping", 2),
    ("scene", 3),
    ("simulation", 4),
    ("runtime", 5),
    ("replay", 6),
    ("report", 6),
];

fn layer(module: &str) -> Option<u8> {
    LAYERS
        .iter()
        .find(|(name, _)| *name == module)
        .map(|&(_, layer)| layer)
}

/// The source with comments, string and character literals blanked out, so that braces and
/// paths inside them are not read as code.
fn code_only(source: &str) -> String {
    let chars: Vec<char> = source.chars().collect();
    let at = |i: usize| chars.get(i).copied();
    let mut out = String::with_capacity(source.len());
    let mut i = 0;
    while i < chars.len() {
        match chars[i] {
            '/' if at(i + 1) == Some('/') => {
                while i < chars.len() && chars[i] != '\n' {
                    i += 1;
                }
            }
            '/' if at(i + 1) == Some('*') => {
                let mut depth = 0;
                while i < chars.len() {
                    if chars[i] == '/' && at(i + 1) == Some('*') {
                        depth += 1;
                        i += 2;
                    } else if chars[i] == '*' && at(i + 1) == Some('/') {
                        depth -= 1;
                        i += 2;
                        if depth == 0 {
                            break;
                        }
                    } else {
                        i += 1;
                    }
                }
            }
            'r' if at(i + 1) == Some('"') || (at(i + 1) == Some('#') && at(i + 2) == Some('"')) => {
                let hashes = chars[i + 1..].iter().take_while(|&&c| c == '#').count();
                i += 2 + hashes;
                while i < chars.len() {
                    if chars[i] == '"' && chars[i + 1..].iter().take(hashes).all(|&c| c == '#') {
                        i += 1 + hashes;
                        break;
                    }
                    i += 1;
                }
                out.push_str("\"\"");
                continue;
            }
            '"' => {
                i += 1;
                while i < chars.len() && chars[i] != '"' {
                    i += if chars[i] == '\\' { 2 } else { 1 };
                }
                i += 1;
                out.push_str("\"\"");
                continue;
            }
            // A character literal ('x', '\n', '{'), not a lifetime ('a in <'a>).
            '\'' if at(i + 2) == Some('\'') || at(i + 1) == Some('\\') => {
                i += 1;
                while i < chars.len() && chars[i] != '\'' {
                    i += if chars[i] == '\\' { 2 } else { 1 };
                }
                i += 1;
                out.push_str("' '");
                continue;
            }
            c => out.push(c),
        }
        i += 1;
    }
    out
}

/// The code without the items under `#[cfg(test)]`, and the names of the test-only modules it
/// declares in files of their own (`#[cfg(test)] mod tests;`).
fn without_tests(code: &str) -> (String, Vec<String>) {
    const MARK: &str = "#[cfg(test)]";
    let mut kept = String::new();
    let mut test_modules = Vec::new();
    let mut rest = code;
    while let Some(at) = rest.find(MARK) {
        kept.push_str(&rest[..at]);
        let item = &rest[at + MARK.len()..];
        let semicolon = item.find(';').unwrap_or(item.len());
        let brace = item.find('{').unwrap_or(item.len());
        if semicolon < brace {
            let words: Vec<&str> = item[..semicolon].split_whitespace().collect();
            if let [.., "mod", name] = words.as_slice() {
                test_modules.push((*name).to_owned());
            }
            rest = &item[(semicolon + 1).min(item.len())..];
        } else {
            let mut depth = 0usize;
            let mut end = item.len();
            for (index, c) in item.char_indices().skip(brace) {
                match c {
                    '{' => depth += 1,
                    '}' => {
                        depth -= 1;
                        if depth == 0 {
                            end = index + 1;
                            break;
                        }
                    }
                    _ => {}
                }
            }
            rest = &item[end..];
        }
    }
    kept.push_str(rest);
    (kept, test_modules)
}

/// Every module of the crate's root that `code` names: `crate::m`, `crate::{m, ..}`, and, in a
/// top-level module's own `mod.rs`, `super::m`.
fn named_modules(code: &str, top_level_file: bool) -> Vec<String> {
    let mut names = Vec::new();
    let prefixes: &[&str] = if top_level_file {
        &["crate::", "super::"]
    } else {
        &["crate::"]
    };
    for prefix in prefixes {
        for (at, _) in code.match_indices(prefix) {
            let before = code[..at].chars().next_back();
            if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
                continue;
            }
            let after = &code[at + prefix.len()..];
            let identifier = |text: &str| -> String {
                text.trim_start()
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect()
            };
            if let Some(group) = after.trim_start().strip_prefix('{') {
                let mut depth = 1;
                let mut start = 0;
                for (index, c) in group.char_indices() {
                    match c {
                        '{' => depth += 1,
                        '}' => depth -= 1,
                        ',' if depth == 1 => {
                            names.push(identifier(&group[start..index]));
                            start = index + 1;
                        }
                        _ => {}
                    }
                    if depth == 0 {
                        names.push(identifier(&group[start..index]));
                        break;
                    }
                }
            } else {
                names.push(identifier(after));
            }
        }
    }
    names.retain(|name| layer(name).is_some());
    names
}

/// The modules of its own layer or above that one source file of `module` names.
fn upward_references(module: &str, source: &str, top_level_file: bool) -> Vec<String> {
    let own = layer(module).expect("a layered module");
    let (code, _) = without_tests(&code_only(source));
    named_modules(&code, top_level_file)
        .into_iter()
        .filter(|name| name != module && layer(name).is_some_and(|other| other >= own))
        .collect()
}

/// The `.rs` files of the module rooted at `dir`, leaving out those that only tests declare.
fn module_files(dir: &Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    let mut pending = vec![dir.join("mod.rs")];
    while let Some(file) = pending.pop() {
        let source = std::fs::read_to_string(&file)
            .unwrap_or_else(|error| panic!("reading {}: {error}", file.display()));
        let (code, test_modules) = without_tests(&code_only(&source));
        let children_dir = match file.file_name().and_then(|name| name.to_str()) {
            Some("mod.rs") => file.parent().expect("a folder").to_owned(),
            _ => file.with_extension(""),
        };
        for words in code
            .split(';')
            .map(|item| item.split_whitespace().collect::<Vec<_>>())
        {
            if let [.., "mod", name] = words.as_slice()
                && !test_modules.iter().any(|test| test == name)
            {
                let flat = children_dir.join(format!("{name}.rs"));
                pending.push(if flat.exists() {
                    flat
                } else {
                    children_dir.join(name).join("mod.rs")
                });
            }
        }
        files.push(file);
    }
    files
}

#[test]
fn no_module_names_a_module_above_it() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut violations = Vec::new();
    let mut files_read = 0;
    for (module, _) in LAYERS {
        let root = src.join(module);
        for file in module_files(&root) {
            let source = std::fs::read_to_string(&file).expect("readable");
            let top_level = file == root.join("mod.rs");
            for name in upward_references(module, &source, top_level) {
                violations.push(format!("{} names {name}", file.display()));
            }
            files_read += 1;
        }
    }
    assert!(files_read > 50, "only {files_read} files found");
    assert!(violations.is_empty(), "{violations:#?}");
}

#[test]
fn the_library_names_no_client_crate() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut naming = Vec::new();
    for (module, _) in LAYERS {
        for file in module_files(&src.join(module)) {
            let source = std::fs::read_to_string(&file).expect("readable");
            if code_only(&source).contains("vas_client") {
                naming.push(file.display().to_string());
            }
        }
    }
    assert!(naming.is_empty(), "{naming:#?}");
}

#[test]
fn an_upward_path_is_found_wherever_it_is_written() {
    let upward = [
        "use crate::scene::Scene;",
        "use crate::{geometry::TriMesh, runtime};",
        "fn f() { let _ = crate::grasping::FLEX_COUNT; }",
        "pub(crate) fn g(x: &crate::sliding::SlideParams) {}",
    ];
    for source in upward {
        assert_eq!(
            upward_references("collision", source, false).len(),
            1,
            "{source}"
        );
    }
    assert_eq!(
        upward_references("geometry", "use super::collision::DopTree;", true),
        ["collision"]
    );
    assert_eq!(
        upward_references("sliding", "use crate::grasping::HandModel;", false),
        ["grasping"]
    );
    assert_eq!(
        upward_references("simulation", "use crate::runtime::loops::Loops;", false),
        ["runtime"]
    );
    assert_eq!(
        upward_references("scene", "use crate::simulation::frames::Stamps;", false),
        ["simulation"]
    );
}

#[test]
fn downward_paths_tests_comments_and_strings_are_not_upward() {
    let fine = "\
use crate::geometry::TriMesh; // crate::scene in a comment
/* crate::runtime::run in a block comment */
const NAME: &str = \"crate::scene::Scene\";
const BRACE: char = '{';
#[cfg(test)]
mod tests {
    use crate::scene::Scene;
    fn nested() { if true { let _ = crate::runtime::run; } }
}
#[cfg(test)]
mod fixtures;
fn after() -> crate::collision::QueryStats { todo!() }
";
    assert!(upward_references("sliding", fine, false).is_empty());
    let (_, test_modules) = without_tests(&code_only(fine));
    assert_eq!(test_modules, ["fixtures"]);
}
