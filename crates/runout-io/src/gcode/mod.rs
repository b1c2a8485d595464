//! ISO G-code: lexer, modal interpretation of linear moves, and a rewriter that offsets the
//! coordinates of motion blocks and keeps every other byte identical (crates.md: own parser with
//! f64 values and spans).
//!
//! ```
//! use runout_io::gcode::{NcProgram, RewriteOptions};
//! let text = "N10 G90 G1 X10.0 Y-2.5 Z5 F1200 (cut)\r\nX11 ; next\r\n";
//! let prog = NcProgram::parse(text).unwrap();
//! assert_eq!(prog.motion_blocks().len(), 2);
//! let same = prog.rewrite(&[None, None], &RewriteOptions::default()).unwrap();
//! assert_eq!(same, text);
//! let moved = prog.rewrite(&[Some([0.001, 0.0, 0.0]), None], &RewriteOptions::default()).unwrap();
//! assert_eq!(moved, "N10 G90 G1 X10.0010 Y-2.5 Z5 F1200 (cut)\r\nX11 ; next\r\n");
//! ```

mod lexer;
mod program;

pub use lexer::{lex, Line, Word};
pub use program::{MotionBlock, NcProgram, RewriteOptions, AXES};

/// A G-code error with its position (1-based line and character column).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("line {line}, column {column}: {message}")]
pub struct NcError {
    /// 1-based line.
    pub line: usize,
    /// 1-based column (characters).
    pub column: usize,
    /// What is wrong and what was expected.
    pub message: String,
}
