//! The one CSV writer of the crate (`sweep.csv`, `bench.csv`, `builds.csv`): rows of text
//! fields, comma-separated, `\n`-terminated, a field quoted (`"` doubled inside) only when it
//! holds a comma, a quote or a line break, through the `csv` crate.

use csv::{QuoteStyle, Terminator, Writer, WriterBuilder};

/// A CSV table built in memory ([`CsvTable::finish`] gives its text).
pub struct CsvTable {
    writer: Writer<Vec<u8>>,
}

impl Default for CsvTable {
    fn default() -> Self {
        Self::new()
    }
}

impl CsvTable {
    /// An empty table (quoting fields only where needed, lines ending in `\n`).
    pub fn new() -> Self {
        let writer = WriterBuilder::new()
            .quote_style(QuoteStyle::Necessary)
            .terminator(Terminator::Any(b'\n'))
            .flexible(true)
            .from_writer(Vec::new());
        Self { writer }
    }

    /// Appends one row.
    pub fn row<I, F>(&mut self, fields: I)
    where
        I: IntoIterator<Item = F>,
        F: AsRef<[u8]>,
    {
        // Writing into a Vec cannot fail (no I/O), and every field is text.
        self.writer.write_record(fields).expect("CSV into memory");
    }

    /// The table's text.
    pub fn finish(self) -> String {
        let bytes = self.writer.into_inner().map_err(|e| e.into_error()).expect("CSV into memory");
        String::from_utf8(bytes).expect("CSV of UTF-8 fields is UTF-8")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(fields: &[&str]) -> String {
        let mut t = CsvTable::new();
        t.row(fields);
        t.finish()
    }

    #[test]
    fn fields_are_quoted_only_when_needed() {
        assert_eq!(line(&["eye.pupil_diameter", "2.5", "inf", ""]), "eye.pupil_diameter,2.5,inf,\n");
        assert_eq!(line(&["[0, 0, 350]", "x"]), "\"[0, 0, 350]\",x\n");
        assert_eq!(line(&["a\"b"]), "\"a\"\"b\"\n");
        assert_eq!(line(&["say \"x\", y"]), "\"say \"\"x\"\", y\"\n");
        assert_eq!(line(&["two\nlines", "cr\r"]), "\"two\nlines\",\"cr\r\"\n");
        // What a hand-written writer would leave bare stays bare: spaces, #, ', non-ASCII.
        assert_eq!(line(&[" a b ", "#1", "it's", "café", "LA3"]), " a b ,#1,it's,café,LA3\n");
    }

    #[test]
    fn rows_of_different_lengths_and_empty_fields() {
        let mut t = CsvTable::new();
        t.row(["point", "id", "method"]);
        t.row(["0", "", "LC"]);
        t.row(["1", "abc"]);
        assert_eq!(t.finish(), "point,id,method\n0,,LC\n1,abc\n");
    }
}
