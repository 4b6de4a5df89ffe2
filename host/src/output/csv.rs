//! CSV with a header row.

use std::io::{self, Write};

use super::format_f64;

/// Writes comma-separated values with a header row. Numbers use [`format_f64`]; text
/// fields are quoted when they contain a comma, a quote or a line break.
pub struct CsvWriter<W: Write> {
    inner: W,
    columns: usize,
}

/// Quotes a CSV field when needed.
pub fn csv_field(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
    }
}

/// The fields of one CSV line as [`csv_field`] writes them (quotes removed, doubled
/// quotes undone).
pub fn csv_fields(line: &str) -> Vec<String> {
    let (mut out, mut cur, mut quoted) = (vec![], String::new(), false);
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                cur.push('"');
                chars.next();
            }
            ('"', _) => quoted = !quoted,
            (',', false) => out.push(std::mem::take(&mut cur)),
            _ => cur.push(c),
        }
    }
    out.push(cur);
    out
}

impl<W: Write> CsvWriter<W> {
    /// Writes the header row.
    pub fn new<S: AsRef<str>>(mut inner: W, columns: &[S]) -> io::Result<Self> {
        let header: Vec<String> = columns.iter().map(|c| csv_field(c.as_ref())).collect();
        writeln!(inner, "{}", header.join(","))?;
        Ok(CsvWriter {
            inner,
            columns: columns.len(),
        })
    }

    fn check(&self, len: usize) -> io::Result<()> {
        if len == self.columns {
            Ok(())
        } else {
            Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("CSV row has {len} fields, the header {}", self.columns),
            ))
        }
    }

    /// Writes a row of numbers.
    pub fn write_row(&mut self, values: &[f64]) -> io::Result<()> {
        self.check(values.len())?;
        let row: Vec<String> = values.iter().map(|&v| format_f64(v)).collect();
        writeln!(self.inner, "{}", row.join(","))
    }

    /// Writes a row of already formatted fields (quoted as needed), for mixed rows.
    pub fn write_record<S: AsRef<str>>(&mut self, fields: &[S]) -> io::Result<()> {
        self.check(fields.len())?;
        let row: Vec<String> = fields.iter().map(|f| csv_field(f.as_ref())).collect();
        writeln!(self.inner, "{}", row.join(","))
    }

    /// Continues a file whose header (of `columns` fields) is already written.
    pub fn resume(inner: W, columns: usize) -> Self {
        CsvWriter { inner, columns }
    }

    /// The underlying writer.
    pub fn get_mut(&mut self) -> &mut W {
        &mut self.inner
    }

    /// Gives the underlying writer back.
    pub fn into_inner(self) -> W {
        self.inner
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_quotes_and_counts() {
        let mut w = CsvWriter::new(Vec::new(), &["time", "outcome"]).unwrap();
        w.write_record(&["1.5", "twisting, late"]).unwrap();
        assert!(w.write_row(&[1.0]).is_err());
        let text = String::from_utf8(w.into_inner()).unwrap();
        assert_eq!(text, "time,outcome\n1.5,\"twisting, late\"\n");
    }
}
