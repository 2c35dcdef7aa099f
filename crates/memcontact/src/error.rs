//! The library's error type: every variant names the entity that failed.

use std::path::PathBuf;

/// Everything that can go wrong in the library, with the file, key or mesh entity at fault.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A mesh is broken: the message names the vertex, triangle or edge.
    #[error("mesh: {0}")]
    Mesh(String),
    /// A mesh or data file could not be read or parsed.
    #[error("{path}: {message}")]
    File {
        /// The file at fault.
        path: PathBuf,
        /// What is wrong with it (with line or section where known).
        message: String,
    },
    /// An expression does not parse or uses an unknown name (a long expression is shown
    /// by its beginning).
    #[error("expression `{}`: {message}", excerpt(expr))]
    Expr {
        /// The expression text.
        expr: String,
        /// What is wrong with it.
        message: String,
    },
    /// Problem data out of range (t ≤ 0, h < 0, NaN, ...): names the quantity.
    #[error("invalid data: {0}")]
    Data(String),
    /// A solver did not converge or met a numerical failure.
    #[error("solver {solver}: {message}")]
    Solver {
        /// The solver's name.
        solver: String,
        /// What happened (iterations, residual reached, ...).
        message: String,
    },
    /// A case (file, dict or value) refused: the key at fault, and where it is.
    #[error("{}", case_message(file.as_deref(), *line, key, message))]
    Case {
        /// The case file, when the case came from one.
        file: Option<PathBuf>,
        /// The 1-based line in the file, when known.
        line: Option<usize>,
        /// The dotted key at fault (`membrane.tension`), empty when the whole case is.
        key: String,
        /// What is wrong.
        message: String,
    },
    /// The run was asked to stop ([`crate::parallel::Cancel`]): Ctrl-C, or its caller.
    #[error("interrupted")]
    Cancelled,
    /// An error with what was being done when it happened (shown as its cause).
    #[error("{context}")]
    Context {
        /// What was being done.
        context: String,
        /// The error.
        #[source]
        source: Box<Error>,
    },
    /// An input/output failure while writing results.
    #[error("{path}: {source}")]
    Io {
        /// The file being written or read.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
}

/// A picture that cannot be drawn is bad data (its message names what).
impl From<memcontact_plot::Error> for Error {
    fn from(e: memcontact_plot::Error) -> Error {
        Error::Data(e.to_string())
    }
}

/// `file:line: key: message`, leaving out what is not known.
fn case_message(
    file: Option<&std::path::Path>,
    line: Option<usize>,
    key: &str,
    message: &str,
) -> String {
    let mut s = String::new();
    if let Some(f) = file {
        s.push_str(&f.display().to_string());
        if let Some(l) = line {
            s.push_str(&format!(":{l}"));
        }
        s.push_str(": ");
    } else if let Some(l) = line {
        s.push_str(&format!("line {l}: "));
    }
    if !key.is_empty() {
        s.push_str(key);
        s.push_str(": ");
    }
    s.push_str(message);
    s
}

/// The longest text quoted whole in a message (characters).
const EXCERPT_CHARS: usize = 80;

/// `text` for a message: whole when short, else its beginning and its length, so that a
/// 400 KB expression or token does not fill the terminal.
pub fn excerpt(text: &str) -> std::borrow::Cow<'_, str> {
    match text.char_indices().nth(EXCERPT_CHARS) {
        None => std::borrow::Cow::Borrowed(text),
        Some((cut, _)) => std::borrow::Cow::Owned(format!(
            "{}… ({} characters)",
            &text[..cut],
            text.chars().count()
        )),
    }
}

impl Error {
    /// This error as the cause of `context` (what was being done).
    pub fn context(self, context: impl Into<String>) -> Error {
        Error::Context {
            context: context.into(),
            source: Box::new(self),
        }
    }

    /// An error about the case as a whole (no key, no file): its message alone.
    pub fn case(message: impl Into<String>) -> Error {
        Error::Case {
            file: None,
            line: None,
            key: String::new(),
            message: message.into(),
        }
    }
}

/// Shorthand for results of this library.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// A value refused by validation: the key (dotted path) and what is wrong.
#[derive(Debug, Clone, PartialEq)]
pub struct Invalid {
    /// The dotted key, e.g. `membrane.tension`.
    pub key: String,
    /// What is wrong.
    pub message: String,
}

impl Invalid {
    /// A refusal of `key`.
    pub fn new(key: impl Into<String>, message: impl Into<String>) -> Invalid {
        Invalid {
            key: key.into(),
            message: message.into(),
        }
    }

    /// The library error, without a file.
    pub fn into_error(self) -> Error {
        Error::Case {
            file: None,
            line: None,
            key: self.key,
            message: self.message,
        }
    }
}
