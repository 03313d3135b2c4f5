//! `docs/wire.md` is the one specification of every message's bytes: its tables must say what
//! the Rust types are (every size, alignment, offset and type, from `size_of`, `align_of` and
//! `offset_of!`), its envelope table the codes and versions the bridge sends, and the C header
//! must name the same fields in the same order. A change to a wire type that the specification
//! does not follow fails here.

use std::collections::BTreeMap;
use std::path::Path;

use vas_bridge::wire::layout::{ALL, Layout};
use vas_bridge::wire::{Code, Message};
use vas_protocol::{
    ClearanceFrame, ControlRequest, ControlResponse, ForceFrame, GeometryHeader, GloveSample,
    HandFrame, HandJointsSample, PartsFrameHeader, SimEvent, TrackerSample,
};

/// One type as the specification gives it.
#[derive(Debug, Default)]
struct Specified {
    size: Option<(usize, usize)>,
    /// `(offset, field, type)` per row.
    rows: Vec<(usize, String, String)>,
}

fn workspace_file(path: &str) -> String {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    std::fs::read_to_string(root.join(path)).unwrap_or_else(|error| panic!("{path}: {error}"))
}

/// The cells of a table row, trimmed, without the outer pipes.
fn cells(line: &str) -> Option<Vec<&str>> {
    let inner = line.trim().strip_prefix('|')?.strip_suffix('|')?;
    Some(inner.split('|').map(str::trim).collect())
}

fn unquote(cell: &str) -> &str {
    cell.trim_matches('`')
}

/// Every `### Type` section of the specification: its size line and its field table.
fn specified_types(spec: &str) -> BTreeMap<String, Specified> {
    let mut types = BTreeMap::new();
    let mut current: Option<String> = None;
    for line in spec.lines() {
        if let Some(heading) = line.strip_prefix("### ") {
            let name = unquote(heading.trim()).to_owned();
            types.insert(name.clone(), Specified::default());
            current = Some(name);
            continue;
        }
        if line.starts_with("## ") {
            current = None;
        }
        let Some(name) = &current else { continue };
        let entry = types.get_mut(name).expect("inserted at its heading");
        // "`HandFrame`: 1128 bytes, alignment 8."
        if let Some(rest) = line.strip_prefix(&format!("`{name}`: ")) {
            let numbers: Vec<usize> = (rest.split(|c: char| !c.is_ascii_digit()))
                .filter_map(|word| word.parse().ok())
                .collect();
            if let [size, align] = numbers[..] {
                entry.size = Some((size, align));
            }
        }
        if let Some(cells) = cells(line)
            && let Ok(offset) = cells[0].parse::<usize>()
        {
            entry.rows.push((
                offset,
                unquote(cells[1]).to_owned(),
                unquote(cells[2]).to_owned(),
            ));
        }
    }
    types
}

/// The rows a layout's table must have.
fn expected_rows(layout: &Layout) -> Vec<(usize, String, String)> {
    (layout.fields.iter())
        .map(|field| (field.offset, field.name.to_owned(), field.kind.spelling()))
        .collect()
}

fn table(rows: &[(usize, String, String)]) -> String {
    (rows.iter())
        .map(|(offset, field, ty)| format!("| {offset} | `{field}` | {ty} |"))
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn every_type_is_specified_as_the_rust_type_lays_it_out() {
    let types = specified_types(&workspace_file("docs/wire.md"));
    let mut wrong = Vec::new();
    for layout in ALL {
        let Some(specified) = types.get(layout.name) else {
            wrong.push(format!("### {} is missing", layout.name));
            continue;
        };
        if specified.size != Some((layout.size, layout.align)) {
            wrong.push(format!(
                "`{}`: {} bytes, alignment {}. (the specification says {:?})",
                layout.name, layout.size, layout.align, specified.size
            ));
        }
        let expected = expected_rows(layout);
        if specified.rows != expected {
            wrong.push(format!(
                "### {}: the rows must be (offset, field, type)\n{}",
                layout.name,
                table(&expected)
            ));
        }
    }
    assert!(
        wrong.is_empty(),
        "docs/wire.md differs from the types:\n\n{}",
        wrong.join("\n\n")
    );
}

/// The envelope table's rows: code, body type, version.
fn envelope_rows(spec: &str) -> Vec<(u32, String, u32)> {
    let section = spec
        .split("## Envelope")
        .nth(1)
        .expect("an Envelope section");
    let section = section.split("\n## ").next().unwrap_or(section);
    (section.lines())
        .filter_map(cells)
        .filter_map(|cells| {
            let code = cells.first()?.parse().ok()?;
            let version = cells.get(2)?.parse().ok()?;
            Some((code, unquote(cells[1]).to_owned(), version))
        })
        .collect()
}

fn row<T: Message>() -> (u32, String, u32) {
    (T::CODE as u32, T::LAYOUT.name.to_owned(), T::version())
}

#[test]
fn the_envelope_table_gives_every_code_and_version() {
    let expected = vec![
        row::<TrackerSample>(),
        row::<GloveSample>(),
        row::<HandJointsSample>(),
        row::<GeometryHeader>(),
        row::<PartsFrameHeader>(),
        row::<HandFrame>(),
        row::<SimEvent>(),
        row::<ForceFrame>(),
        row::<ClearanceFrame>(),
        row::<ControlRequest>(),
        row::<ControlResponse>(),
    ];
    assert_eq!(Code::ControlResponse as u32, 21);
    let specified = envelope_rows(&workspace_file("docs/wire.md"));
    assert_eq!(
        specified, expected,
        "docs/wire.md's envelope table must be (code, body, version): {expected:?}"
    );
}

/// The field names of the C header's `typedef struct { ... } Vas<name>;`, if it declares one.
fn c_fields(header: &str, name: &str) -> Option<Vec<String>> {
    let end = header.find(&format!("}} Vas{name};"))?;
    let start = header[..end].rfind("typedef struct {")?;
    let body = &header[start + "typedef struct {".len()..end];
    let mut fields = Vec::new();
    let mut in_comment = false;
    for line in body.lines().map(str::trim) {
        if line.starts_with("/*") {
            in_comment = true;
        }
        if in_comment {
            in_comment = !line.ends_with("*/");
            continue;
        }
        if let Some(declaration) = line.strip_suffix(';') {
            let declarator = declaration.split_whitespace().last()?;
            fields.push(declarator.split('[').next()?.to_owned());
        }
    }
    Some(fields)
}

#[test]
fn the_c_header_declares_the_specified_fields_in_order() {
    let header = workspace_file("client-c/include/vas_client.h");
    let mut compared = 0;
    for layout in ALL {
        let Some(fields) = c_fields(&header, layout.name) else {
            continue;
        };
        let names: Vec<&str> = layout.fields.iter().map(|field| field.name).collect();
        assert_eq!(fields, names, "Vas{} in vas_client.h", layout.name);
        compared += 1;
    }
    // The frames, samples, poses and stamps a C renderer or device reads and writes.
    assert!(
        compared >= 10,
        "only {compared} types of the header compared"
    );
}
