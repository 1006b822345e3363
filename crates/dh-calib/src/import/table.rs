//! Plain numeric tables: an optional header line, then rows of numbers.

use crate::csv::{number, records, DataError, Record};

/// A numeric row with its 1-based line.
#[derive(Debug)]
pub(crate) struct Row {
    pub line: usize,
    pub values: Vec<f64>,
}

/// How cells are separated.
#[derive(Clone, Copy)]
pub(crate) enum Delimiter {
    Comma,
    Whitespace,
}

/// Reads a table of `width` numbers per row. The first line is a header (and is skipped) when
/// any of its cells is not a number; column names in errors come from the header, else
/// the 1-based column number.
///
/// # Errors
/// [`DataError::FieldCount`], [`DataError::NotANumber`], [`DataError::NonFinite`], or
/// [`DataError::Empty`] when there are no data rows.
pub(crate) fn read(text: &str, delimiter: Delimiter, width: usize) -> Result<Vec<Row>, DataError> {
    let recs = match delimiter {
        Delimiter::Comma => records(text, ',', true)?,
        Delimiter::Whitespace => text
            .split('\n')
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'))
            .map(|(i, l)| Record {
                line: i + 1,
                fields: l.split_whitespace().map(String::from).collect(),
            })
            .collect(),
    };
    let mut header: Option<&Record> = None;
    let mut body = recs.as_slice();
    if let Some((first, rest)) = recs.split_first() {
        if first
            .fields
            .iter()
            .any(|f| f.trim().parse::<f64>().is_err())
        {
            header = Some(first);
            body = rest;
        }
    }
    if body.is_empty() {
        return Err(DataError::Empty {
            found: if header.is_some() {
                "only a header"
            } else {
                "an empty file"
            },
        });
    }
    if let Some(h) = header {
        if h.fields.len() != width {
            return Err(DataError::FieldCount {
                line: h.line,
                expected: width,
                found: h.fields.len(),
            });
        }
    }
    let name = |i: usize| match header {
        Some(h) => h.fields[i].clone(),
        None => (i + 1).to_string(),
    };
    body.iter()
        .map(|r| {
            if r.fields.len() != width {
                return Err(DataError::FieldCount {
                    line: r.line,
                    expected: width,
                    found: r.fields.len(),
                });
            }
            let values = r
                .fields
                .iter()
                .enumerate()
                .map(|(i, f)| number(f, r.line, &name(i)))
                .collect::<Result<_, _>>()?;
            Ok(Row {
                line: r.line,
                values,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_is_optional_and_names_columns_in_errors() {
        let rows = read("a,b\n1,2\n3,4\n", Delimiter::Comma, 2).unwrap();
        assert_eq!(rows.len(), 2);
        assert_eq!((rows[1].line, rows[1].values.clone()), (3, vec![3.0, 4.0]));
        let rows = read("1 2\n\n3   4\n", Delimiter::Whitespace, 2).unwrap();
        assert_eq!(rows[1].line, 3);
        let e = read("a,b\n1,x2\n", Delimiter::Comma, 2).unwrap_err();
        assert_eq!(
            e.to_string(),
            "line 2, column 'b': expected a number, found 'x2'"
        );
        let e = read("1 2\n1 2 3\n", Delimiter::Whitespace, 2).unwrap_err();
        assert_eq!(e.to_string(), "line 2: expected 2 fields, found 3");
    }
}
