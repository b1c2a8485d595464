//! Error messages for people: one line with every cause printed once, and what to do about
//! operating-system errors.
//!
//! Rule for the error types of this workspace: a `Display` includes the text of its cause **or**
//! exposes the cause through [`Error::source`], never both (otherwise a chain printer shows the
//! cause twice: `cannot read: Is a directory (os error 21): Is a directory (os error 21)`).
//! [`chain_message`] also drops a cause whose text the message already contains, so an error
//! type from a dependency that breaks the rule is still printed once.

use std::error::Error;

/// `error: cause: cause of the cause …` with each cause printed once: a cause whose text is
/// already part of the message so far (because an outer `Display` included it) is skipped. An
/// [`std::io::Error`] in the chain is printed with what to do ([`io_problem`]).
///
/// ```
/// #[derive(Debug)]
/// struct Outer(std::io::Error);
/// impl std::fmt::Display for Outer {
///     fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
///         write!(f, "data.csv: cannot read: {}", self.0) // includes its cause …
///     }
/// }
/// impl std::error::Error for Outer {
///     fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
///         Some(&self.0) // … and exposes it: breaks the rule, still printed once
///     }
/// }
/// let e = Outer(std::io::Error::other("disk on fire"));
/// assert_eq!(runout_io::report::chain_message(&e), "data.csv: cannot read: disk on fire");
/// ```
pub fn chain_message(err: &(dyn Error + 'static)) -> String {
    chain_of(std::iter::successors(Some(err), |&e| e.source()))
}

/// [`chain_message`] over an already walked chain (outermost first), e.g. `anyhow::Error::chain`.
///
/// A cause that starts with the file the message so far ends with (`analysing rec.csv` then
/// `rec.csv:3: …`) continues it without naming the file again (`analysing rec.csv:3: …`).
pub fn chain_of<'a>(chain: impl IntoIterator<Item = &'a (dyn Error + 'static)>) -> String {
    let mut out = String::new();
    for e in chain {
        let raw = e.to_string();
        if raw.trim().is_empty() || out.contains(raw.trim()) {
            continue;
        }
        // an operating-system error says what to do about it
        let text = match e.downcast_ref::<std::io::Error>() {
            Some(io) => io_problem(io),
            None => raw,
        };
        let text = text.trim();
        let last = out.rsplit(' ').next().unwrap_or("");
        match text.strip_prefix(last) {
            Some(rest) if last.len() > 1 && rest.starts_with(':') => out.push_str(rest),
            _ => {
                if !out.is_empty() {
                    out.push_str(": ");
                }
                out.push_str(text);
            }
        }
    }
    out
}

/// An operating-system error as `what happened; what to do` (the advice for the common kinds:
/// missing file, folder given for a file, no permission).
///
/// ```
/// let e = std::fs::File::open("/no/such/file.csv").unwrap_err();
/// let m = runout_io::report::io_problem(&e);
/// assert!(m.starts_with("No such file or directory") && m.contains("check the path"), "{m}");
/// ```
pub fn io_problem(e: &std::io::Error) -> String {
    use std::io::ErrorKind as K;
    let hint = match e.kind() {
        K::NotFound => "check the path (relative paths start at the current folder)",
        K::IsADirectory => "expected a file, got a folder",
        K::PermissionDenied => "check the file's permissions",
        _ => return e.to_string(),
    };
    format!("{e}; {hint}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn causes_are_printed_once() {
        #[derive(Debug, thiserror::Error)]
        #[error("outer")]
        struct Outer(#[source] Middle);
        #[derive(Debug, thiserror::Error)]
        #[error("middle: {0}")]
        struct Middle(#[source] std::io::Error);
        let e = Outer(Middle(std::io::Error::other("root cause")));
        assert_eq!(chain_message(&e), "outer: middle: root cause");
    }

    #[test]
    fn a_file_named_by_the_context_is_not_repeated() {
        #[derive(Debug, thiserror::Error)]
        #[error("analysing {0}")]
        struct Context(&'static str, #[source] Inner);
        #[derive(Debug, thiserror::Error)]
        #[error("{0}")]
        struct Inner(&'static str);
        let m = |c, i| chain_message(&Context(c, Inner(i)));
        assert_eq!(
            m("d/r.csv", "d/r.csv:3:2: bad"),
            "analysing d/r.csv:3:2: bad"
        );
        assert_eq!(
            m("d/r.csv", "d/r.csv: cannot read"),
            "analysing d/r.csv: cannot read"
        );
        assert_eq!(
            m("d/r.csv", "d/r.csvx: other"),
            "analysing d/r.csv: d/r.csvx: other"
        );
        assert_eq!(
            m("a", "a: b"),
            "analysing a: a: b",
            "one letter is no file name"
        );
    }

    #[test]
    fn os_errors_in_the_chain_get_their_hint_once() {
        #[derive(Debug, thiserror::Error)]
        #[error("creating out.csv")]
        struct Creating(#[source] std::io::Error);
        #[derive(Debug, thiserror::Error)]
        #[error("out.csv: {0}")]
        struct Both(#[source] std::io::Error);
        let nf = || std::io::Error::from(std::io::ErrorKind::NotFound);
        let m = chain_message(&Creating(nf()));
        assert!(
            m.starts_with("creating out.csv: ")
                && m.ends_with("; check the path (relative paths start at the current folder)"),
            "{m}"
        );
        let m = chain_message(&Both(nf()));
        assert_eq!(
            m,
            format!("out.csv: {}", nf()),
            "already printed by the outer error"
        );
    }
}
