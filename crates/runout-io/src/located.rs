//! The error of every text-table reader that points into a file: `file[:line[:column]]: message`
//! (peak tables, FRF tables, the bounded text reader shared by all tables).

/// An input error located in a file. `Display` gives `file[:line[:column]]: message`, the line
/// left out for a problem with the whole file (line 0) and the column when unknown.
///
/// ```
/// use runout_io::LocatedError;
/// let e = LocatedError::new("peaks.csv", 3, "expected a number of newtons, got `abc`").at_column(2);
/// assert_eq!(e.to_string(), "peaks.csv:3:2: expected a number of newtons, got `abc`");
/// assert_eq!(LocatedError::new("frf.csv", 0, "empty").to_string(), "frf.csv: empty");
/// ```
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{file}{}{}: {message}", if *line > 0 { format!(":{line}") } else { String::new() }, column.map(|c| format!(":{c}")).unwrap_or_default())]
pub struct LocatedError {
    /// The file, as given.
    pub file: String,
    /// 1-based line (0 = the whole file).
    pub line: usize,
    /// 1-based column (field), if known.
    pub column: Option<usize>,
    /// What is wrong and what was expected.
    pub message: String,
}

impl LocatedError {
    /// An error at `line` of `file` (0 = the whole file), column unknown.
    pub fn new(file: impl Into<String>, line: usize, message: impl Into<String>) -> Self {
        LocatedError {
            file: file.into(),
            line,
            column: None,
            message: message.into(),
        }
    }

    /// The same error at 1-based `column`.
    pub fn at_column(mut self, column: usize) -> Self {
        self.column = Some(column);
        self
    }

    /// The line as an option (`None` for the whole file).
    pub fn line(&self) -> Option<usize> {
        (self.line > 0).then_some(self.line)
    }
}
