//! Storm's explicit DRN format ("direct encoding"), read and written: the
//! DTMCs, CTMCs, MDPs and Markov automata that Storm builds, exports
//! (`--exportbuild model.drn`) and reads, with their labels and reward
//! models.
//!
//! ```text
//! // comment
//! @type: Markov Automaton          DTMC | CTMC | MDP | Markov Automaton
//! @value_type: double
//! @parameters
//!                                  (empty: no parameters)
//! @reward_models
//! time cost
//! @nr_states
//! 3
//! @nr_choices
//! 4
//! @model
//! state 0 !0 [0, 0] init           id, exit rate (CTMC, MA), state rewards, labels
//!     action t0 [0, 1]             name, action rewards
//!         1 : 0.5                  target : probability (a rate in a CTMC)
//!         2 : 0.5
//! ```
//!
//! # Reading ([`read_drn`])
//!
//! - The header's sections may come in any order; `@type`, `@nr_states` and
//!   `@model` are required, `@nr_choices` is checked when given.
//!   `@value_type` must be `double` (or absent); parameters (parametric
//!   models), intervals and POMDP observations are refused by name.
//!   `@placeholders` (`$name : value`) are resolved.
//! - States must be numbered `0, 1, …` in order; their count must be the
//!   declared one (a shorter file is reported as truncated). Targets must
//!   be states. Values are decimal numbers (`0.5`, `1e-7`, `1/3`), finite
//!   and ≥ 0; entries of value 0 are dropped.
//! - Each row of probabilities must sum to 1, and the rates of a CTMC state
//!   to its exit rate, within `1e-6` per entry (Storm prints six
//!   significant digits by default); the values are kept as written.
//! - A CTMC state with exit rate 0 and no transition (absorbing) gets a
//!   self-loop of rate 1, as PRISM and Storm make of deadlocks; a Markov
//!   automaton's state with exit rate `E > 0` is Markovian and has one row
//!   of probabilities, with `E = 0` it is probabilistic.
//! - In a DTMC or CTMC the `action` line is optional; more than one row
//!   per state is an error.
//! - The initial states are those labelled `init` (at least one).
//! - Every error names the file and the line. The file is read whole; the
//!   memory guard ([`DrnParams::max_memory`]) is checked from the header's
//!   counts and the file's size before anything large is allocated.
//! - The body is parsed in parallel chunks cut at `state` lines; the
//!   result, and the first error reported, are the same on any number of
//!   threads.
//!
//! # Writing ([`write_drn`])
//!
//! The header Storm writes, one `state` block per state (labels quoted when
//! they hold whitespace, a comment after the state line when the caller
//! gives one — a net's marking), one `action` per row (Markovian rows
//! `action 0`), values in Rust's shortest round-trip notation, so that
//! reading a file back gives the same bits. A Markovian row of a model in
//! rate form ([`Model::rate_rows`]) is written as rates in a CTMC and as
//! `rate / E` in a Markov automaton.

use std::collections::HashMap;
use std::io::Write;
use std::path::Path;

use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::mdp::{Model, ModelType, RewardVectors};
use crate::reachability::default_max_memory;

/// Options of [`read_drn`].
#[derive(Debug, Clone)]
pub struct DrnParams {
    /// Refuse ([`Error::MemoryLimit`]) a file whose model would need more
    /// bytes than this (estimated from the header and the file's size).
    /// Default: [`default_max_memory`].
    pub max_memory: u64,
}

impl Default for DrnParams {
    fn default() -> Self {
        DrnParams {
            max_memory: default_max_memory(),
        }
    }
}

/// Bytes of a chunk of the body parsed by one task.
const CHUNK_BYTES: usize = 1 << 22;
/// Tolerance on a row's sum, per entry.
const SUM_TOLERANCE: f64 = 1e-6;

struct Header {
    model_type: ModelType,
    reward_names: Vec<String>,
    nr_states: usize,
    nr_choices: Option<usize>,
    placeholders: HashMap<String, f64>,
    /// Line number of `@model` (1-based) and byte offset of the body.
    model_line: usize,
    body: usize,
}

fn format_error(source: &str, line: usize, message: impl Into<String>) -> Error {
    Error::Format {
        location: format!("{source}:{line}"),
        message: message.into(),
    }
}

/// Lines of `text` with their 1-based numbers and byte offsets of the next.
struct Lines<'a> {
    text: &'a str,
    pos: usize,
    line: usize,
}

impl<'a> Iterator for Lines<'a> {
    type Item = (usize, &'a str);
    fn next(&mut self) -> Option<(usize, &'a str)> {
        if self.pos >= self.text.len() {
            return None;
        }
        let rest = &self.text[self.pos..];
        let end = rest.find('\n').unwrap_or(rest.len());
        let line = rest[..end].strip_suffix('\r').unwrap_or(&rest[..end]);
        self.pos += end + 1;
        self.line += 1;
        Some((self.line, line))
    }
}

fn model_type(name: &str) -> Option<ModelType> {
    match name.trim() {
        "DTMC" | "dtmc" => Some(ModelType::Dtmc),
        "CTMC" | "ctmc" => Some(ModelType::Ctmc),
        "MDP" | "mdp" => Some(ModelType::Mdp),
        "MA" | "Markov Automaton" | "MarkovAutomaton" | "ma" => Some(ModelType::MarkovAutomaton),
        _ => None,
    }
}

fn parse_header(text: &str, source: &str) -> Result<Header> {
    let mut lines = Lines {
        text,
        pos: 0,
        line: 0,
    };
    let mut model_type_seen = None;
    let mut reward_names = Vec::new();
    let mut nr_states = None;
    let mut nr_choices = None;
    let mut placeholders = HashMap::new();
    let next_value = |lines: &mut Lines<'_>, what: &str, at: usize| -> Result<(usize, String)> {
        lines
            .next()
            .map(|(l, s)| (l, s.trim().to_string()))
            .ok_or_else(|| format_error(source, at, format!("the file ends after {what}")))
    };
    while let Some((no, line)) = lines.next() {
        let t = line.trim();
        if t.is_empty() || t.starts_with("//") {
            continue;
        }
        if let Some(name) = t.strip_prefix("@type:") {
            if model_type_seen.is_some() {
                return Err(format_error(source, no, "@type is declared twice"));
            }
            model_type_seen = Some(model_type(name).ok_or_else(|| {
                format_error(
                    source,
                    no,
                    format!(
                        "model type `{}` is not supported (DTMC, CTMC, MDP, Markov Automaton are)",
                        name.trim()
                    ),
                )
            })?);
        } else if let Some(v) = t.strip_prefix("@value_type:") {
            if v.trim() != "double" {
                return Err(format_error(
                    source,
                    no,
                    format!("value type `{}`: only `double` models are supported", v.trim()),
                ));
            }
        } else if t == "@parameters" {
            let (l, params) = next_value(&mut lines, "@parameters", no)?;
            if !params.is_empty() {
                return Err(format_error(
                    source,
                    l,
                    format!("parametric models are not supported (parameters: {params})"),
                ));
            }
        } else if t == "@reward_models" {
            let (_, names) = next_value(&mut lines, "@reward_models", no)?;
            reward_names = names.split_whitespace().map(str::to_string).collect();
        } else if t == "@nr_states" {
            let (l, v) = next_value(&mut lines, "@nr_states", no)?;
            nr_states =
                Some(v.parse::<usize>().map_err(|_| {
                    format_error(source, l, format!("@nr_states: `{v}` is not a whole number"))
                })?);
        } else if t == "@nr_choices" {
            let (l, v) = next_value(&mut lines, "@nr_choices", no)?;
            nr_choices =
                Some(v.parse::<usize>().map_err(|_| {
                    format_error(source, l, format!("@nr_choices: `{v}` is not a whole number"))
                })?);
        } else if t == "@placeholders" {
            while text[lines.pos..].starts_with('$') {
                let Some((l, p)) = lines.next() else { break };
                let (name, value) = p
                    .split_once(':')
                    .ok_or_else(|| format_error(source, l, "a placeholder without `:`"))?;
                let value = parse_value(value.trim(), &placeholders).ok_or_else(|| {
                    format_error(
                        source,
                        l,
                        format!("placeholder value `{}` is not a number", value.trim()),
                    )
                })?;
                placeholders.insert(name.trim().trim_start_matches('$').to_string(), value);
            }
        } else if t == "@model" {
            let model_type =
                model_type_seen.ok_or_else(|| format_error(source, no, "@model before @type"))?;
            let nr_states = nr_states.ok_or_else(|| format_error(source, no, "@model before @nr_states"))?;
            return Ok(Header {
                model_type,
                reward_names,
                nr_states,
                nr_choices,
                placeholders,
                model_line: no,
                body: lines.pos.min(text.len()),
            });
        } else {
            return Err(format_error(
                source,
                no,
                format!("unexpected line in the header: `{t}`"),
            ));
        }
    }
    Err(format_error(source, lines.line, "the file ends before @model"))
}

/// A decimal number, `a/b`, or `$placeholder`.
fn parse_value(t: &str, placeholders: &HashMap<String, f64>) -> Option<f64> {
    if let Some(name) = t.strip_prefix('$') {
        return placeholders.get(name).copied();
    }
    if let Some((a, b)) = t.split_once('/') {
        let (a, b) = (a.trim().parse::<f64>().ok()?, b.trim().parse::<f64>().ok()?);
        return Some(a / b);
    }
    t.parse::<f64>().ok()
}

/// What one chunk of the body holds.
#[derive(Default)]
struct Chunk {
    first_state: Option<(usize, u64)>,
    exit: Vec<f64>,
    state_rewards: Vec<f64>,
    labels: Vec<(u32, u32)>,
    label_names: Vec<String>,
    /// Rows of each state: counts.
    rows_of: Vec<u32>,
    entries_of: Vec<u32>,
    col: Vec<u32>,
    val: Vec<f64>,
    row_names: Vec<u32>,
    action_names: Vec<String>,
    /// Indices of `label_names` and `action_names` (names looked up once
    /// each, not by a scan: a file of many distinct names stays linear).
    label_ids: HashMap<String, u32>,
    action_ids: HashMap<String, u32>,
    action_rewards: Vec<f64>,
    any_state_reward: Vec<bool>,
    any_action_reward: Vec<bool>,
}

struct Parser<'a> {
    source: &'a str,
    header: &'a Header,
}

/// The current state's row under construction.
struct Open {
    line: usize,
    state: u64,
    exit: f64,
    sum: f64,
    entries: u32,
    has_row: bool,
}

impl Parser<'_> {
    fn err(&self, line: usize, message: impl Into<String>) -> Error {
        format_error(self.source, line, message)
    }

    fn value(&self, t: &str, line: usize, what: &str) -> Result<f64> {
        let v = parse_value(t, &self.header.placeholders)
            .ok_or_else(|| self.err(line, format!("{what} `{t}` is not a number")))?;
        if !(v.is_finite() && v >= 0.0) {
            return Err(self.err(line, format!("{what} {t} must be a finite number ≥ 0")));
        }
        Ok(v)
    }

    /// `[r1, r2]` at the start of `rest`: the values and what follows.
    fn rewards<'t>(
        &self,
        rest: &'t str,
        line: usize,
        out: &mut Vec<f64>,
        any: &mut [bool],
    ) -> Result<&'t str> {
        let k = self.header.reward_names.len();
        let base = out.len();
        out.resize(base + k, 0.0);
        let rest = rest.trim_start();
        let Some(inner) = rest.strip_prefix('[') else {
            return Ok(rest);
        };
        let end = inner
            .find(']')
            .ok_or_else(|| self.err(line, "`]` missing after the rewards"))?;
        for (i, t) in inner[..end].split(',').enumerate() {
            let t = t.trim();
            if i >= k.max(1) && !t.is_empty() {
                return Err(self.err(line, format!("more rewards than the {k} reward models declared")));
            }
            let v = parse_value(t, &self.header.placeholders)
                .filter(|v| v.is_finite())
                .ok_or_else(|| self.err(line, format!("reward `{t}` is not a finite number")))?;
            if i < k {
                out[base + i] = v;
                if v != 0.0 {
                    any[i] = true;
                }
            }
        }
        Ok(&inner[end + 1..])
    }

    fn close_row(&self, open: &mut Open, c: &mut Chunk) -> Result<()> {
        if !open.has_row {
            return Ok(());
        }
        let rates = self.header.model_type == ModelType::Ctmc;
        let expected = if rates { open.exit } else { 1.0 };
        if rates && open.entries == 0 && open.exit == 0.0 {
            // An absorbing CTMC state: a self-loop of rate 1.
            c.col.push(open.state as u32);
            c.val.push(1.0);
            *c.exit.last_mut().unwrap_or(&mut 0.0) = 1.0;
            open.entries = 1;
        } else {
            let tol = SUM_TOLERANCE * f64::from(open.entries.max(1)) * expected.max(f64::MIN_POSITIVE);
            let within = (open.sum - expected).abs() <= tol;
            if !within {
                return Err(self.err(
                    open.line,
                    format!(
                        "the {} of state {}'s row sum to {}, not {}",
                        if rates { "rates" } else { "probabilities" },
                        open.state,
                        open.sum,
                        expected
                    ),
                ));
            }
        }
        c.entries_of.push(open.entries);
        open.has_row = false;
        open.sum = 0.0;
        open.entries = 0;
        Ok(())
    }

    fn open_row(
        &self,
        open: &mut Open,
        c: &mut Chunk,
        line: usize,
        name: &str,
        any: &mut [bool],
        rest: &str,
    ) -> Result<()> {
        self.close_row(open, c)?;
        if let Some(rows) = c.rows_of.last_mut() {
            *rows += 1;
            let deterministic = !self.header.model_type.is_nondeterministic();
            if *rows > 1 && (deterministic || open.exit > 0.0) {
                return Err(self.err(
                    line,
                    format!(
                        "state {} has a second action; {} has one",
                        open.state,
                        if deterministic {
                            "every state of a Markov chain"
                        } else {
                            "a Markovian state (exit rate > 0)"
                        }
                    ),
                ));
            }
        }
        let id = intern(&mut c.action_names, &mut c.action_ids, name);
        c.row_names.push(id);
        let after = self.rewards(rest, line, &mut c.action_rewards, any)?;
        if !after.trim().is_empty() {
            return Err(self.err(
                line,
                format!("unexpected text after the action: `{}`", after.trim()),
            ));
        }
        open.has_row = true;
        open.line = line;
        Ok(())
    }

    fn state_line(
        &self,
        c: &mut Chunk,
        open: &mut Open,
        line: usize,
        rest: &str,
        expected: &mut u64,
    ) -> Result<()> {
        self.close_row(open, c)?;
        let (id, mut rest) = rest
            .trim_start()
            .split_once(char::is_whitespace)
            .unwrap_or((rest.trim(), ""));
        let id: u64 = id
            .parse()
            .map_err(|_| self.err(line, format!("state id `{id}` is not a whole number")))?;
        if c.first_state.is_none() {
            c.first_state = Some((line, id));
            *expected = id;
        }
        if id != *expected {
            return Err(self.err(
                line,
                format!("states must be numbered in order without gaps: expected state {expected}, got {id}"),
            ));
        }
        if id as usize >= self.header.nr_states {
            return Err(self.err(
                line,
                format!(
                    "state {id} is beyond the {} states declared (@nr_states)",
                    self.header.nr_states
                ),
            ));
        }
        *expected += 1;
        let mut exit = 0.0;
        if self.header.model_type.is_continuous() {
            let r = rest.trim_start();
            let Some(r) = r.strip_prefix('!') else {
                return Err(self.err(line, format!("state {id}: the exit rate (`!rate`) is missing")));
            };
            let (e, after) = r.split_once(char::is_whitespace).unwrap_or((r, ""));
            exit = self.value(e, line, "exit rate")?;
            rest = after;
        }
        if rest.trim_start().starts_with('{') {
            return Err(self.err(line, "observations (POMDPs) are not supported"));
        }
        c.exit.push(exit);
        let mut any = std::mem::take(&mut c.any_state_reward);
        let rest = self.rewards(rest, line, &mut c.state_rewards, &mut any)?;
        c.any_state_reward = any;
        let local = c.rows_of.len() as u32;
        for label in labels(rest) {
            let label = label.map_err(|m| self.err(line, m))?;
            let i = intern(&mut c.label_names, &mut c.label_ids, label);
            c.labels.push((local, i));
        }
        c.rows_of.push(0);
        *open = Open {
            line,
            state: id,
            exit,
            sum: 0.0,
            entries: 0,
            has_row: false,
        };
        Ok(())
    }

    fn entry_line(&self, c: &mut Chunk, open: &mut Open, line: usize, t: &str) -> Result<()> {
        if c.rows_of.is_empty() {
            return Err(self.err(line, format!("a transition before any state: `{t}`")));
        }
        if !open.has_row {
            if self.header.model_type.is_nondeterministic()
                && c.rows_of.last().copied().unwrap_or(0) == 0
                && open.exit <= 0.0
            {
                return Err(self.err(
                    line,
                    format!("state {}: a transition before any `action`", open.state),
                ));
            }
            let mut any = std::mem::take(&mut c.any_action_reward);
            self.open_row(open, c, line, "0", &mut any, "")?;
            c.any_action_reward = any;
        }
        let (target, value) = t
            .split_once(':')
            .ok_or_else(|| self.err(line, format!("expected `target : value`, got `{t}`")))?;
        let target = target.trim();
        let target: u64 = target
            .parse()
            .map_err(|_| self.err(line, format!("target `{target}` is not a state number")))?;
        if target as usize >= self.header.nr_states {
            return Err(self.err(
                line,
                format!(
                    "target state {target} is out of range: the model has {} states",
                    self.header.nr_states
                ),
            ));
        }
        let what = if self.header.model_type == ModelType::Ctmc {
            "rate"
        } else {
            "probability"
        };
        let v = self.value(value.trim(), line, what)?;
        if what == "probability" && v > 1.0 + SUM_TOLERANCE {
            return Err(self.err(line, format!("probability {v} is greater than 1")));
        }
        open.sum += v;
        if v > 0.0 {
            c.col.push(target as u32);
            c.val.push(v);
            open.entries += 1;
        }
        Ok(())
    }

    /// Parses one chunk of the body starting at line `first_line`.
    fn chunk(&self, text: &str, first_line: usize) -> Result<Chunk> {
        let k = self.header.reward_names.len();
        let mut c = Chunk {
            any_state_reward: vec![false; k],
            any_action_reward: vec![false; k],
            ..Chunk::default()
        };
        let mut open = Open {
            line: first_line,
            state: 0,
            exit: 0.0,
            sum: 0.0,
            entries: 0,
            has_row: false,
        };
        let mut expected = 0u64;
        let lines = Lines {
            text,
            pos: 0,
            line: first_line - 1,
        };
        for (no, raw) in lines {
            let t = raw.trim_start();
            if t.is_empty() || t.starts_with("//") {
                continue;
            }
            if let Some(rest) = t.strip_prefix("state ") {
                self.state_line(&mut c, &mut open, no, rest, &mut expected)?;
            } else if let Some(rest) = t.strip_prefix("action ") {
                if c.rows_of.is_empty() {
                    return Err(self.err(no, "an action before any state"));
                }
                let rest = rest.trim_start();
                let (name, rest) = rest.split_once(char::is_whitespace).unwrap_or((rest, ""));
                let mut any = std::mem::take(&mut c.any_action_reward);
                self.open_row(&mut open, &mut c, no, name, &mut any, rest)?;
                c.any_action_reward = any;
            } else if t.starts_with(|ch: char| ch.is_ascii_digit()) {
                self.entry_line(&mut c, &mut open, no, t.trim_end())?;
            } else {
                return Err(self.err(no, format!("unexpected line: `{}`", t.trim_end())));
            }
        }
        self.close_row(&mut open, &mut c)?;
        if c.rows_of.last() == Some(&0) {
            return Err(self.err(open.line, format!("state {} has no transition", open.state)));
        }
        if let Some(i) = c.rows_of.iter().position(|&r| r == 0) {
            let state = c.first_state.map_or(0, |f| f.1) + i as u64;
            return Err(self.err(open.line, format!("state {state} has no transition")));
        }
        Ok(c)
    }
}

/// The labels of a state line: whitespace-separated, optionally quoted.
fn labels(rest: &str) -> impl Iterator<Item = std::result::Result<&str, String>> {
    let mut rest = rest.trim_start();
    std::iter::from_fn(move || {
        rest = rest.trim_start();
        if rest.is_empty() {
            return None;
        }
        if let Some(r) = rest.strip_prefix('"') {
            let Some(end) = r.find('"') else {
                rest = "";
                return Some(Err("a label's opening `\"` is not closed".to_string()));
            };
            let label = &r[..end];
            rest = &r[end + 1..];
            return Some(Ok(label));
        }
        let end = rest.find(char::is_whitespace).unwrap_or(rest.len());
        let label = &rest[..end];
        rest = &rest[end..];
        Some(Ok(label))
    })
}

/// Cuts the body into chunks at `state` lines: byte ranges.
fn chunks(body: &str) -> Vec<(usize, usize)> {
    let bytes = body.as_bytes();
    let mut cuts = vec![0];
    let mut at = CHUNK_BYTES;
    while at < bytes.len() {
        match body[at..].find("\nstate ") {
            Some(k) => {
                let cut = at + k + 1;
                cuts.push(cut);
                at = cut + CHUNK_BYTES;
            }
            None => break,
        }
    }
    cuts.push(bytes.len());
    cuts.windows(2).map(|w| (w[0], w[1])).collect()
}

/// Estimated bytes of the model a file describes: the text, plus per state
/// and per entry what the model holds (entries bounded by the text's size:
/// a transition line takes at least 6 bytes).
fn estimated_bytes(header: &Header, text_len: usize) -> u64 {
    let states = header.nr_states as u64;
    let rows = header.nr_choices.unwrap_or(header.nr_states) as u64;
    let entries = ((text_len - header.body.min(text_len)) / 6) as u64;
    let k = header.reward_names.len() as u64;
    text_len as u64 + states * (4 + 8 + 8 * k + 1) + rows * (8 + 4 + 8 * k) + entries * 12
}

/// Reads a DRN model from `text` (see the module docs); `source` names it
/// in errors.
pub fn read_drn(text: &str, source: &str, params: &DrnParams) -> Result<Model> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let header = parse_header(text, source)?;
    let estimate = estimated_bytes(&header, text.len());
    if estimate > params.max_memory {
        return Err(Error::MemoryLimit {
            estimate,
            limit: params.max_memory,
            markings: header.nr_states,
            edges: (text.len() - header.body) / 6,
        });
    }
    let body = &text[header.body..];
    let ranges = chunks(body);
    // Line numbers where each chunk starts.
    let newlines: Vec<usize> = ranges
        .par_iter()
        .map(|&(a, b)| body.as_bytes()[a..b].iter().filter(|&&c| c == b'\n').count())
        .collect();
    let mut first_lines = Vec::with_capacity(ranges.len());
    let mut line = header.model_line + 1;
    for n in &newlines {
        first_lines.push(line);
        line += n;
    }
    let parser = Parser {
        source,
        header: &header,
    };
    let parsed: Vec<Result<Chunk>> = ranges
        .par_iter()
        .zip(&first_lines)
        .map(|(&(a, b), &l)| parser.chunk(&body[a..b], l))
        .collect();
    let mut chunks = Vec::with_capacity(parsed.len());
    for c in parsed {
        chunks.push(c?);
    }
    let budget = Budget {
        estimate,
        limit: params.max_memory,
    };
    assemble(&header, chunks, source, line, budget)
}

/// Reads a DRN file.
pub fn read_drn_file(path: impl AsRef<Path>, params: &DrnParams) -> Result<Model> {
    let path = path.as_ref();
    let io = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let len = std::fs::metadata(path).map_err(io)?.len();
    if len > params.max_memory {
        return Err(Error::MemoryLimit {
            estimate: len,
            limit: params.max_memory,
            markings: 0,
            edges: 0,
        });
    }
    let text = std::fs::read_to_string(path).map_err(io)?;
    read_drn(&text, &path.display().to_string(), params)
}

/// The chunks joined into one model, checked across chunks: states
/// numbered in order over the chunks, their count and the actions' the
/// declared ones.
fn assemble(
    header: &Header,
    chunks: Vec<Chunk>,
    source: &str,
    last_line: usize,
    budget: Budget,
) -> Result<Model> {
    let mut expected = 0u64;
    for c in &chunks {
        if let Some((line, first)) = c.first_state {
            if first != expected {
                return Err(format_error(
                    source,
                    line,
                    format!(
                        "states must be numbered in order without gaps: expected state {expected}, got {first}"
                    ),
                ));
            }
            expected += c.rows_of.len() as u64;
        }
    }
    let n = expected as usize;
    if n != header.nr_states {
        return Err(format_error(
            source,
            last_line,
            format!(
                "the file ends after {n} of the {} states declared (@nr_states): truncated?",
                header.nr_states
            ),
        ));
    }
    let rows: usize = chunks.iter().map(|c| c.entries_of.len()).sum();
    if let Some(declared) = header.nr_choices.filter(|&d| d != rows) {
        return Err(format_error(
            source,
            last_line,
            format!("the file has {rows} actions, but @nr_choices declares {declared}"),
        ));
    }
    join(header, chunks, n, rows, source, budget)
}

/// The memory the header's estimate takes and the limit it is held to
/// ([`DrnParams::max_memory`]); the labels, which the header does not
/// count, are checked against it as they are joined.
#[derive(Debug, Clone, Copy)]
struct Budget {
    estimate: u64,
    limit: u64,
}

/// The checked chunks concatenated: rows, entries, exit rates, labels
/// (`init` giving the initial states), rewards and action names.
fn join(
    header: &Header,
    chunks: Vec<Chunk>,
    n: usize,
    rows: usize,
    source: &str,
    budget: Budget,
) -> Result<Model> {
    let k = header.reward_names.len();
    let entries: usize = chunks.iter().map(|c| c.col.len()).sum();
    let mut row_start = Vec::with_capacity(n + 1);
    let mut entry_start = Vec::with_capacity(rows + 1);
    let mut col = Vec::with_capacity(entries);
    let mut val = Vec::with_capacity(entries);
    let mut exit = Vec::with_capacity(if header.model_type.is_continuous() { n } else { 0 });
    let mut labels: Vec<(String, Vec<bool>)> = Vec::new();
    let mut label_ids: HashMap<String, usize> = HashMap::new();
    let mut action_names: Vec<String> = Vec::new();
    let mut action_ids: HashMap<String, u32> = HashMap::new();
    let mut row_action = Vec::with_capacity(rows);
    let mut state_rewards = vec![Vec::with_capacity(n); k];
    let mut action_rewards = vec![Vec::with_capacity(rows); k];
    let (mut any_state, mut any_action) = (vec![false; k], vec![false; k]);
    row_start.push(0u32);
    entry_start.push(0u64);
    let mut state_base = 0u32;
    for c in chunks {
        for &r in &c.rows_of {
            row_start.push(row_start.last().copied().unwrap_or(0) + r);
        }
        for &e in &c.entries_of {
            entry_start.push(entry_start.last().copied().unwrap_or(0) + u64::from(e));
        }
        col.extend_from_slice(&c.col);
        val.extend_from_slice(&c.val);
        if header.model_type.is_continuous() {
            exit.extend_from_slice(&c.exit);
        }
        let ids: Vec<u32> = c
            .action_names
            .iter()
            .map(|name| intern(&mut action_names, &mut action_ids, name))
            .collect();
        row_action.extend(c.row_names.iter().map(|&i| ids[i as usize]));
        for &(s, l) in &c.labels {
            let name = &c.label_names[l as usize];
            let i = match label_ids.get(name) {
                Some(&i) => i,
                None => {
                    // A label is a flag per state: the model's memory grows
                    // by a state count per distinct label.
                    let estimate = budget.estimate + (labels.len() as u64 + 1) * n as u64;
                    if estimate > budget.limit {
                        return Err(Error::MemoryLimit {
                            estimate,
                            limit: budget.limit,
                            markings: n,
                            edges: entries,
                        });
                    }
                    labels.push((name.clone(), vec![false; n]));
                    label_ids.insert(name.clone(), labels.len() - 1);
                    labels.len() - 1
                }
            };
            labels[i].1[(state_base + s) as usize] = true;
        }
        for j in 0..k {
            state_rewards[j].extend(c.state_rewards.iter().skip(j).step_by(k.max(1)));
            action_rewards[j].extend(c.action_rewards.iter().skip(j).step_by(k.max(1)));
            any_state[j] |= c.any_state_reward[j];
            any_action[j] |= c.any_action_reward[j];
        }
        state_base += c.rows_of.len() as u32;
    }
    let initial: Vec<u32> = labels
        .iter()
        .find(|(name, _)| name == "init")
        .map(|(_, s)| (0..n as u32).filter(|&i| s[i as usize]).collect())
        .unwrap_or_default();
    if initial.is_empty() {
        return Err(format_error(
            source,
            header.model_line,
            "no state is labelled `init`: the model has no initial state",
        ));
    }
    let rate_rows = header.model_type == ModelType::Ctmc;
    let mut model = Model::from_parts(
        header.model_type,
        row_start,
        entry_start,
        col,
        val,
        exit,
        rate_rows,
        initial,
    );
    for (name, states) in labels {
        model.set_label(&name, states);
    }
    for (j, name) in header.reward_names.iter().enumerate() {
        model.set_reward(RewardVectors {
            name: name.clone(),
            state: any_state[j].then(|| std::mem::take(&mut state_rewards[j])),
            action: any_action[j].then(|| std::mem::take(&mut action_rewards[j])),
        });
    }
    model.set_action_names(action_names, row_action);
    Ok(model)
}

/// The index of `name` in `names` (`ids` indexes them), added at the end
/// when new.
fn intern(names: &mut Vec<String>, ids: &mut HashMap<String, u32>, name: &str) -> u32 {
    if let Some(&i) = ids.get(name) {
        return i;
    }
    let i = names.len() as u32;
    names.push(name.to_string());
    ids.insert(name.to_string(), i);
    i
}

/// A value in the notation that reads back as the same `f64`.
fn push_value(out: &mut Vec<u8>, v: f64) {
    if v == v.trunc() && v.abs() < 1e15 {
        let _ = write!(out, "{}", v as i64);
    } else {
        let _ = write!(out, "{v:?}");
    }
}

/// A name DRN can hold in an action line (whitespace becomes `_`).
fn action_token(name: &str) -> String {
    let t: String = name
        .chars()
        .map(|c| if c.is_whitespace() { '_' } else { c })
        .collect();
    if t.is_empty() { "_".into() } else { t }
}

/// Writes `model` in DRN (see the module docs); `comment(s)`, when given,
/// is written as a comment line after state `s`'s line.
pub fn write_drn(
    model: &Model,
    out: &mut dyn Write,
    comment: Option<&dyn Fn(usize) -> String>,
) -> Result<()> {
    let io = |source: std::io::Error| Error::Io {
        path: "the DRN output".into(),
        source,
    };
    for r in model.rewards() {
        if r.name.is_empty() || r.name.contains(char::is_whitespace) {
            return Err(Error::Invalid(format!(
                "DRN cannot hold a reward model named `{}` (names are separated by whitespace)",
                r.name
            )));
        }
    }
    if let Some(l) = model
        .labels()
        .iter()
        .find(|l| l.name.contains('"') || l.name.is_empty())
    {
        return Err(Error::Invalid(format!("DRN cannot hold the label `{}`", l.name)));
    }
    let mut buf: Vec<u8> = Vec::with_capacity(1 << 20);
    let ty = model.model_type();
    let _ = writeln!(
        buf,
        "// Exported by petrinav\n// Original model type: {}",
        ty.drn_name()
    );
    let _ = writeln!(
        buf,
        "@type: {}\n@value_type: double\n@parameters\n",
        ty.drn_name()
    );
    let names: Vec<&str> = model.rewards().iter().map(|r| r.name.as_str()).collect();
    let _ = writeln!(buf, "@reward_models\n{}", names.join(" "));
    let _ = writeln!(
        buf,
        "@nr_states\n{}\n@nr_choices\n{}\n@model",
        model.num_states(),
        model.num_rows()
    );
    // Labels of each state.
    let mut state_labels: Vec<Vec<u32>> = vec![Vec::new(); model.num_states()];
    for (i, l) in model.labels().iter().enumerate() {
        for (s, &x) in l.states.iter().enumerate() {
            if x {
                state_labels[s].push(i as u32);
            }
        }
    }
    let rewards = model.rewards();
    for s in 0..model.num_states() {
        let _ = write!(buf, "state {s}");
        let e = model.exit_rate(s);
        if ty.is_continuous() {
            buf.extend_from_slice(b" !");
            push_value(&mut buf, e);
        }
        if !rewards.is_empty() {
            buf.extend_from_slice(b" [");
            for (i, r) in rewards.iter().enumerate() {
                if i > 0 {
                    buf.extend_from_slice(b", ");
                }
                push_value(&mut buf, r.state.as_ref().map_or(0.0, |v| v[s]));
            }
            buf.push(b']');
        }
        for &l in &state_labels[s] {
            let name = &model.labels()[l as usize].name;
            if name.contains(char::is_whitespace) {
                let _ = write!(buf, " \"{name}\"");
            } else {
                let _ = write!(buf, " {name}");
            }
        }
        buf.push(b'\n');
        if let Some(c) = comment {
            let text = c(s);
            for line in text.lines() {
                let _ = writeln!(buf, "//{line}");
            }
        }
        let scale = model.rate_rows() && e > 0.0 && ty == ModelType::MarkovAutomaton;
        let unscale = !model.rate_rows() && e > 0.0 && ty == ModelType::Ctmc;
        for r in model.rows(s) {
            let _ = write!(buf, "\taction {}", action_token(&model.action_name(r)));
            if !rewards.is_empty() {
                buf.extend_from_slice(b" [");
                for (i, rw) in rewards.iter().enumerate() {
                    if i > 0 {
                        buf.extend_from_slice(b", ");
                    }
                    push_value(&mut buf, rw.action.as_ref().map_or(0.0, |v| v[r]));
                }
                buf.push(b']');
            }
            buf.push(b'\n');
            for (t, v) in model.row_entries(r) {
                let v = if scale {
                    v / e
                } else if unscale {
                    v * e
                } else {
                    v
                };
                let _ = write!(buf, "\t\t{t} : ");
                push_value(&mut buf, v);
                buf.push(b'\n');
            }
        }
        if buf.len() >= 1 << 20 {
            out.write_all(&buf).map_err(io)?;
            buf.clear();
        }
    }
    out.write_all(&buf).map_err(io)?;
    Ok(())
}
