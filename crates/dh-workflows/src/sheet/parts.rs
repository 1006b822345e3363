//! Reading a large YAML sheet a part at a time.
//!
//! The YAML reader holds every event of a document at once: about 5 kB per joint of a written
//! table with its pairs, 500 MB for a chain of 100 000 joints. A sheet's long lists, `joints`
//! and `pairs`, are block sequences at the top level, and their items are independent: each
//! is read on its own, a thousand at a time, and the rest of the document (with those lists
//! emptied) on its own. Only documents whose layout makes this the same reading are read so:
//! the list's key alone on its line at column 0, every item starting with `- ` at column 0 and
//! every other line of the list indented (or blank). Anything else, and any part the YAML
//! reader refuses (an alias to an anchor in another part, a quoted text running onto a line at
//! column 0), sends the whole document to the whole-document reader, whose messages say where
//! and what.

use std::ops::Range;

use serde::de::DeserializeOwned;

use super::SheetDoc;

/// Documents shorter than this (bytes) are read whole.
pub(crate) const PARTS_MIN_BYTES: usize = 1 << 20;

/// Items of a list read together.
const ITEMS_PER_PART: usize = 1000;

/// The keys whose lists are read in parts.
const LISTS: [&str; 2] = ["joints", "pairs"];

/// A top-level block sequence: the byte range from its key's line to its last line, and the
/// byte range of each item.
struct Block {
    whole: Range<usize>,
    items: Vec<Range<usize>>,
}

/// `text` read a part at a time (see the module docs), `None` when its layout does not allow
/// it or a part is refused.
pub(crate) fn read_in_parts(text: &str) -> Option<SheetDoc> {
    let blocks: Vec<(&str, Block)> = LISTS
        .iter()
        .filter_map(|key| block_sequence(text, key).map(|b| (*key, b)))
        .collect();
    if blocks.is_empty() {
        return None;
    }
    let mut head = String::with_capacity(1024);
    let mut at = 0;
    let mut order: Vec<&(&str, Block)> = blocks.iter().collect();
    order.sort_by_key(|(_, b)| b.whole.start);
    for (key, b) in &order {
        head.push_str(text.get(at..b.whole.start)?);
        head.push_str(key);
        head.push_str(": []\n");
        at = b.whole.end;
    }
    head.push_str(text.get(at..)?);
    let mut doc: SheetDoc = serde_yaml::from_str(&head).ok()?;
    for (key, b) in &blocks {
        match *key {
            "joints" => doc.joints = items(text, &b.items)?,
            _ => doc.pairs = Some(items(text, &b.items)?),
        }
    }
    Some(doc)
}

/// The items of `ranges` read [`ITEMS_PER_PART`] at a time, the parts on the machine's cores
/// ([`dh_core::parallel`]).
fn items<T: DeserializeOwned + Send>(text: &str, ranges: &[Range<usize>]) -> Option<Vec<T>> {
    let parts: Vec<&[Range<usize>]> = ranges.chunks(ITEMS_PER_PART).collect();
    let read = dh_core::parallel::map(parts.len(), |k| {
        let part = parts[k];
        let (first, last) = (part.first()?, part.last()?);
        let read: Vec<T> = serde_yaml::from_str(text.get(first.start..last.end)?).ok()?;
        (read.len() == part.len()).then_some(read)
    })?;
    let mut out = Vec::with_capacity(ranges.len());
    for part in read {
        out.extend(part?);
    }
    Some(out)
}

/// The YAML of `doc` as [`serde_yaml::to_string`] writes it, its `joints` and `pairs` written
/// [`ITEMS_PER_PART`] at a time on the machine's cores when they are longer. The writer puts
/// a top-level list's key alone on its line and each item at column 0 (`- name: j0`), as it
/// writes a list of its own, so the parts joined are the whole document's text.
///
/// # Errors
/// What the YAML writer refuses.
pub(crate) fn write_in_parts(doc: &SheetDoc) -> Result<String, serde_yaml::Error> {
    let long = |n: usize| n > ITEMS_PER_PART;
    let pairs = doc.pairs.as_deref().unwrap_or_default();
    if !long(doc.joints.len()) && !long(pairs.len()) {
        return serde_yaml::to_string(doc);
    }
    let mut head = doc.clone();
    head.joints.clear();
    if let Some(p) = head.pairs.as_mut() {
        p.clear();
    }
    let mut text = serde_yaml::to_string(&head)?;
    if !doc.joints.is_empty() {
        text = splice(&text, "joints", &list_in_parts(&doc.joints)?);
    }
    if !pairs.is_empty() {
        text = splice(&text, "pairs", &list_in_parts(pairs)?);
    }
    Ok(text)
}

/// `items` as the YAML writer writes a list, [`ITEMS_PER_PART`] at a time in parallel.
fn list_in_parts<T: serde::Serialize + Sync>(items: &[T]) -> Result<String, serde_yaml::Error> {
    let parts: Vec<&[T]> = items.chunks(ITEMS_PER_PART).collect();
    let written = dh_core::parallel::try_map(
        parts.len(),
        |k| serde_yaml::to_string(parts[k]),
        || serde::ser::Error::custom("a writer thread lost its part"),
    )?;
    Ok(written.concat())
}

/// `text` with the line `<key>: []` at column 0 replaced by `<key>:` and `list`.
fn splice(text: &str, key: &str, list: &str) -> String {
    let empty = format!("{key}: []\n");
    let at = text
        .match_indices(&empty)
        .find(|(i, _)| *i == 0 || text.as_bytes()[i - 1] == b'\n')
        .map(|(i, _)| i);
    match at {
        Some(i) => format!("{}{key}:\n{list}{}", &text[..i], &text[i + empty.len()..]),
        None => text.to_owned(),
    }
}

/// The block sequence of the top-level `key`, when the document holds it once, in the layout
/// the module docs describe.
fn block_sequence(text: &str, key: &str) -> Option<Block> {
    let mut offset = 0;
    let mut found: Option<Block> = None;
    let mut open = false;
    for line in text.split_inclusive('\n') {
        let start = offset;
        offset += line.len();
        let bare = line.trim_end_matches(['\n', '\r']);
        if open {
            let b = found.as_mut()?;
            if let Some(rest) = bare.strip_prefix("- ") {
                if rest.trim().is_empty() {
                    return None;
                }
                b.items.push(start..offset);
                b.whole.end = offset;
                continue;
            }
            if bare.trim().is_empty() || bare.starts_with(' ') {
                let last = b.items.last_mut()?;
                last.end = offset;
                b.whole.end = offset;
                continue;
            }
            if bare.starts_with('#') || bare.starts_with('\t') || bare.starts_with('-') {
                return None;
            }
            open = false;
        }
        if bare == format!("{key}:") {
            if found.is_some() {
                return None;
            }
            found = Some(Block {
                whole: start..offset,
                items: Vec::new(),
            });
            open = true;
        }
    }
    found.filter(|b| !b.items.is_empty())
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEAD: &str = "convention: standard\nlength_unit: m\nangle_unit: rad\n";

    fn joints(n: usize) -> String {
        (0..n)
            .map(|i| format!("- name: j{i}\n  type: revolute\n  a: {i}.0\n  alpha: 0.5\n  d: 0.0\n  theta: 0.0\n"))
            .collect()
    }

    #[test]
    fn a_long_list_reads_as_the_whole_document_does() {
        let text = format!("{HEAD}joints:\n{}warnings: []\n", joints(2500));
        let parts = read_in_parts(&text).unwrap();
        let whole: SheetDoc = serde_yaml::from_str(&text).unwrap();
        assert_eq!(parts.joints.len(), 2500);
        assert_eq!(
            serde_yaml::to_string(&parts).unwrap(),
            serde_yaml::to_string(&whole).unwrap()
        );
    }

    #[test]
    fn a_long_list_is_written_as_the_whole_document_is() {
        let names = [
            "j",
            "yes",
            "'q'",
            "a: b",
            "1e3",
            "x\"y",
            "gelenk_ä",
            "- z",
            "#c",
            "",
        ];
        let rows: String = (0..2500)
            .map(|i| {
                let n = serde_json::to_string(&format!("{}{i}", names[i % names.len()])).unwrap();
                format!("- {{name: {n}, type: revolute, a: {i}.25, alpha: 0.5, d: -0.0, theta: 1e-300}}\n")
            })
            .collect();
        let pairs: String = (0..1500)
            .map(|i| {
                format!("- {{joints: [a{i}, b{i}], relation: skew, distance: {i}.5, angle: 0.1}}\n")
            })
            .collect();
        for pairs in ["", &format!("pairs:\n{pairs}")] {
            let text = format!("{HEAD}joints:\n{rows}{pairs}warnings: [w]\n");
            let doc: SheetDoc = serde_yaml::from_str(&text).unwrap();
            assert_eq!(
                write_in_parts(&doc).unwrap(),
                serde_yaml::to_string(&doc).unwrap()
            );
        }
    }

    #[test]
    fn layouts_it_cannot_split_go_to_the_whole_reader() {
        // A flow list, an indented list, an anchor used in another part, a comment at column 0.
        let flow = format!(
            "{HEAD}joints: [{{name: a, type: revolute, a: 0, alpha: 0, d: 0, theta: 0}}]\n"
        );
        assert!(read_in_parts(&flow).is_none());
        let indented = format!("{HEAD}joints:\n  - name: a\n");
        assert!(read_in_parts(&indented).is_none());
        let alias = format!("{HEAD}joints:\n{}- name: b\n  type: revolute\n  a: *x\n  alpha: 0.5\n  d: 0.0\n  theta: 0.0\n", joints(1000).replacen("a: 0.0", "a: &x 0.0", 1));
        assert!(read_in_parts(&alias).is_none());
        let comment = format!("{HEAD}joints:\n{}# note\n{}", joints(1), joints(1));
        assert!(read_in_parts(&comment).is_none());
        let twice = format!("{HEAD}joints:\n{}joints:\n{}", joints(1), joints(1));
        assert!(read_in_parts(&twice).is_none());
    }
}
