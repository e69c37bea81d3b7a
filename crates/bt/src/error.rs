//! `bt::Error`: what went wrong, with the file, the line and the node's path.

use std::path::PathBuf;

/// Errors of reading, checking, translating and analysing behaviour trees.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file could not be read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// The XML is not well formed (truncated, unclosed element, …).
    #[error("{file}:{line}:{column}: malformed XML: {message}")]
    Xml {
        /// The file.
        file: String,
        /// 1-based line.
        line: u32,
        /// 1-based column.
        column: u32,
        /// The parser's message.
        message: String,
    },
    /// The XML is well formed but is not a behaviour tree as BehaviorTree.CPP reads it.
    #[error("{file}:{line}: {path}: {message}")]
    Tree {
        /// The file.
        file: String,
        /// 1-based line of the element.
        line: u32,
        /// The node's path in the tree (see [`crate::tree::Node::path`]).
        path: String,
        /// What is wrong.
        message: String,
    },
    /// A node kind that is neither built in nor declared in a `TreeNodesModel`.
    #[error(
        "{file}:{line}: {path}: unknown {role} node `{id}` (declare it in a <TreeNodesModel> or check its spelling)"
    )]
    UnknownNode {
        /// The file.
        file: String,
        /// 1-based line.
        line: u32,
        /// The node's path.
        path: String,
        /// `control` (it has children) or `decorator`.
        role: &'static str,
        /// Its element name or `ID`.
        id: String,
    },
    /// A node kind that is known but whose semantics are not modelled.
    #[error("{file}:{line}: {path}: `{id}` is not supported: {reason}")]
    Unsupported {
        /// The file.
        file: String,
        /// 1-based line.
        line: u32,
        /// The node's path.
        path: String,
        /// Its element name or `ID`.
        id: String,
        /// Why, and what to do instead.
        reason: String,
    },
    /// A parameter of the TOML sidecar (or of a log) is missing, malformed
    /// or out of range.
    #[error("{file}:{line}: [{table}] {field} = {value}: {requirement}")]
    Param {
        /// The file.
        file: String,
        /// 1-based line (0 when unknown).
        line: u32,
        /// The table, e.g. `leaf.FollowPath`.
        table: String,
        /// The field.
        field: String,
        /// The value as written.
        value: String,
        /// What it must be.
        requirement: String,
    },
    /// A log (BehaviorTree.CPP's or our JSONL) could not be read.
    #[error("{file}: {location}: {message}")]
    Log {
        /// The file.
        file: String,
        /// Where: a line, a byte offset or a record.
        location: String,
        /// What is wrong.
        message: String,
    },
    /// The tree cannot be analysed (e.g. it never finishes, or loops in zero time).
    #[error("{0}")]
    Analysis(String),
    /// The Petri-net engine failed.
    #[error(transparent)]
    Petri(#[from] petri::Error),
}

/// `Result<T, bt::Error>`.
pub type Result<T> = std::result::Result<T, Error>;
