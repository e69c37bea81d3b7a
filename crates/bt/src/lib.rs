//! Behaviour trees in: BehaviorTree.CPP (v3 and v4) and Nav2 XML trees read,
//! checked for structural faults, translated to a GSPN and quantified with
//! the Petri-net engine, and cross-checked by a tick-based Monte Carlo
//! interpreter that shares nothing with the translation.
//!
//! ```
//! use bt::{ReadOptions, TreeParams, analyze, read_str};
//!
//! let xml = r#"<root BTCPP_format="4">
//!   <BehaviorTree ID="Fetch">
//!     <Fallback>
//!       <SearchTable/>
//!       <SearchDrawer/>
//!     </Fallback>
//!   </BehaviorTree>
//! </root>"#;
//! let tree = read_str(xml, "fetch.xml", None, &ReadOptions::default())?;
//! let params = TreeParams::parse(
//!     "[leaf.SearchTable]\np_success = 0.1\nmean_time = 5\n\
//!      [leaf.SearchDrawer]\np_success = 0.8\nmean_time = 20\n",
//!     "fetch.toml",
//! )?;
//! let report = analyze(&tree, &params, &bt::AnalyzeOptions::default())?;
//! // Fallback: P(success) = 0.1 + 0.9 · 0.8.
//! assert!((report.p_success - 0.82).abs() < 1e-12);
//! // Mean time: 5 s, plus 20 s when the table search fails.
//! assert!((report.mean_time - (5.0 + 0.9 * 20.0)).abs() < 1e-9);
//! # Ok::<(), bt::Error>(())
//! ```
//!
//! | step | module |
//! |---|---|
//! | read XML (subtrees, includes, models) | [`read`], [`model`], [`tree`] |
//! | per-leaf parameters (TOML sidecar) | [`params`] |
//! | structural checks | [`mod@check`] |
//! | translation to a GSPN | [`translate`], [`formula`] |
//! | analysis (probabilities, times, shares, sensitivities) | [`analyze`](mod@analyze) |
//! | Monte Carlo interpreter | [`montecarlo`] |
//! | drawing the tree | [`svg`] |
//! | parameters from execution logs | [`logs`] |
#![warn(missing_docs)]

pub mod analyze;
pub mod check;
pub mod error;
pub mod formula;
pub mod logs;
pub mod model;
pub mod montecarlo;
pub mod params;
pub mod read;
pub mod svg;
pub mod translate;
pub mod tree;

pub use analyze::{AnalyzeOptions, Report, analyze};
pub use check::{Finding, FindingKind, check};
pub use error::{Error, Result};
pub use params::TreeParams;
pub use read::{ReadOptions, read_file, read_str};
pub use tree::{Kind, Node, NodeId, Tree};
