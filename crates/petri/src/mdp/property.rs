//! Properties in the syntax of PRISM and Storm.
//!
//! ```text
//! property := P dir "=?" "[" "F" state "]"                 probability of reaching
//!           | T dir "=?" "[" "F" state "]"                 expected time to reach
//!           | R [ "{" "\"" name "\"" "}" ] dir "=?" "[" ( "F" state | "LRA" | "S" ) "]"
//!                                                          expected reward to reach, long-run average reward
//!           | LRA dir "=?" "[" state "]"                   long-run fraction of time in state
//! dir      := "min" | "max" | (nothing: for Markov chains)
//! state    := a quoted label ("goal"), a marking expression (#P3 = 1),
//!             or both combined with & | ! (and, or, not), = != < <= > >=
//! ```
//!
//! A quoted name is a label (a DRN label, or a named marking set of a net);
//! `#P` is the token count of place `P` (nets only); `true` and `false` are
//! what they say; a bare name is a parameter of the net. PRISM's `&`, `|`
//! and `!` are read as `and`, `or` and `not` of the expression language
//! ([`crate::expr`]). Unsupported (refused by name): time and step bounds
//! (`F<=10`), cumulative and instantaneous rewards, nested `P`/`R`
//! operators.

use std::fmt;

use crate::error::{Error, Result};
use crate::expr::Expr;

/// Optimise towards the smallest or the largest value.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Direction {
    /// The smallest value over all policies.
    Min,
    /// The largest value over all policies.
    Max,
}

impl Direction {
    /// `min` or `max`.
    pub fn name(self) -> &'static str {
        match self {
            Direction::Min => "min",
            Direction::Max => "max",
        }
    }
}

/// A state formula: an expression whose quoted names are labels.
#[derive(Debug, Clone, PartialEq)]
pub struct StateFormula {
    /// The expression (labels appear as parameters).
    pub expr: Expr,
}

impl StateFormula {
    /// The label, if the formula is one quoted name and nothing else.
    pub fn as_label(&self) -> Option<&str> {
        match &self.expr {
            Expr::Param(n) => Some(n),
            _ => None,
        }
    }
}

/// What a property asks for.
#[derive(Debug, Clone, PartialEq)]
pub enum Query {
    /// `P [F φ]`: the probability of eventually reaching φ.
    Reach(StateFormula),
    /// `T [F φ]`: the expected time (steps in discrete time) to reach φ.
    Time(StateFormula),
    /// `R{"r"} [F φ]`: the expected reward accumulated until φ is reached.
    Reward(Option<String>, StateFormula),
    /// `R{"r"} [LRA]`: the long-run average reward (per unit of time).
    RewardLra(Option<String>),
    /// `LRA [φ]`: the long-run fraction of time spent in φ.
    Lra(StateFormula),
}

/// A parsed property.
#[derive(Debug, Clone, PartialEq)]
pub struct Property {
    /// As written.
    pub text: String,
    /// `min` or `max` (`None`: not given, for Markov chains).
    pub direction: Option<Direction>,
    /// What is asked.
    pub query: Query,
}

impl fmt::Display for Property {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.text)
    }
}

struct Scanner<'a> {
    text: &'a str,
    rest: &'a str,
}

impl<'a> Scanner<'a> {
    fn error(&self, message: impl Into<String>) -> Error {
        Error::Property {
            text: self.text.to_string(),
            message: message.into(),
        }
    }

    fn skip_ws(&mut self) {
        self.rest = self.rest.trim_start();
    }

    fn eat(&mut self, token: &str) -> bool {
        self.skip_ws();
        match self.rest.strip_prefix(token) {
            Some(r) => {
                self.rest = r;
                true
            }
            None => false,
        }
    }

    fn expect(&mut self, token: &str, what: &str) -> Result<()> {
        if self.eat(token) {
            Ok(())
        } else {
            Err(self.error(format!("expected {what} at `{}`", shown(self.rest))))
        }
    }

    fn direction(&mut self) -> Option<Direction> {
        if self.eat("min") {
            Some(Direction::Min)
        } else if self.eat("max") {
            Some(Direction::Max)
        } else {
            None
        }
    }
}

fn shown(rest: &str) -> &str {
    if rest.is_empty() { "the end" } else { rest }
}

impl Property {
    /// Parses a property (see the module docs).
    ///
    /// ```
    /// use petri::mdp::{Direction, Property, Query};
    /// let p = Property::parse(r#"Tmin=? [F "done" & #P1 = 0]"#)?;
    /// assert_eq!(p.direction, Some(Direction::Min));
    /// assert!(matches!(p.query, Query::Time(_)));
    /// # Ok::<(), petri::Error>(())
    /// ```
    pub fn parse(text: &str) -> Result<Property> {
        let mut s = Scanner { text, rest: text };
        s.skip_ws();
        // An optional `"name":` prefix, as in PRISM property files.
        if s.rest.starts_with('"') {
            if let Some(end) = s.rest[1..].find('"') {
                let after = s.rest[end + 2..].trim_start();
                if let Some(r) = after.strip_prefix(':') {
                    s.rest = r;
                }
            }
        }
        s.skip_ws();
        let (op, reward) = if s.eat("LRA") {
            ("LRA", None)
        } else if s.eat("P") {
            ("P", None)
        } else if s.eat("T") {
            ("T", None)
        } else if s.eat("R") {
            let name = if s.eat("{") {
                s.expect("\"", "a quoted reward model name after `{`")?;
                let end = s
                    .rest
                    .find('"')
                    .ok_or_else(|| s.error("the reward model's name is not closed by `\"`"))?;
                let name = s.rest[..end].to_string();
                s.rest = &s.rest[end + 1..];
                s.expect("}", "`}` after the reward model's name")?;
                Some(name)
            } else {
                None
            };
            ("R", Some(name))
        } else if s.eat("S") {
            return Err(s.error("steady-state probabilities (S=?) are `gspn solve --measure`; here write LRA=? [φ] for a long-run fraction"));
        } else {
            return Err(s.error("expected P, T, R or LRA at the start (e.g. Pmax=? [F \"goal\"])"));
        };
        let direction = s.direction();
        if s.eat("=?") {
        } else if s.rest.trim_start().starts_with(['<', '>', '=']) {
            return Err(s.error("bounds (>= 0.5) are not supported: ask for the value with =?"));
        } else {
            return Err(s.error(format!(
                "expected min, max or =? at `{}`",
                shown(s.rest.trim_start())
            )));
        }
        s.expect("[", "`[`")?;
        s.skip_ws();
        let body = s
            .rest
            .strip_suffix(']')
            .or_else(|| s.rest.trim_end().strip_suffix(']'));
        let Some(body) = body else {
            return Err(s.error("the path formula is not closed by `]`"));
        };
        let body = body.trim();
        let query = match op {
            "LRA" => Query::Lra(state_formula(text, body)?),
            "R" if body == "LRA" || body == "S" => Query::RewardLra(reward.flatten()),
            _ => {
                let Some(target) = body.strip_prefix('F') else {
                    return Err(Error::Property {
                        text: text.into(),
                        message: format!(
                            "path formula `{body}`: only eventually (F φ){} is supported",
                            if op == "R" { ", LRA and S" } else { "" }
                        ),
                    });
                };
                if target.starts_with(['<', '>', '[', '=']) {
                    return Err(Error::Property {
                        text: text.into(),
                        message: "time and step bounds (F<=T) are not supported".into(),
                    });
                }
                let phi = state_formula(text, target)?;
                match op {
                    "P" => Query::Reach(phi),
                    "T" => Query::Time(phi),
                    _ => Query::Reward(reward.flatten(), phi),
                }
            }
        };
        Ok(Property {
            text: text.trim().to_string(),
            direction,
            query,
        })
    }

    /// The reward model the property names (`R{"cost"}`), if any.
    pub fn reward_name(&self) -> Option<&str> {
        match &self.query {
            Query::Reward(r, _) | Query::RewardLra(r) => r.as_deref(),
            _ => None,
        }
    }
}

/// A state formula in PRISM syntax, rewritten into the expression
/// language (`&` → `and`, `|` → `or`, `!` → `not`, outside quotes).
pub fn state_formula(property: &str, text: &str) -> Result<StateFormula> {
    let mut out = String::with_capacity(text.len() + 8);
    let mut chars = text.chars().peekable();
    let mut quoted = false;
    while let Some(c) = chars.next() {
        if c == '"' {
            quoted = !quoted;
            out.push(c);
            continue;
        }
        if quoted {
            out.push(c);
            continue;
        }
        match c {
            '&' if chars.peek() != Some(&'&') => out.push_str(" and "),
            '|' if chars.peek() != Some(&'|') => out.push_str(" or "),
            '&' | '|' => {
                chars.next();
                out.push_str(if c == '&' { " and " } else { " or " });
            }
            '!' if chars.peek() != Some(&'=') => out.push_str(" not "),
            c => out.push(c),
        }
    }
    if out.trim().is_empty() {
        return Err(Error::Property {
            text: property.into(),
            message: "the state formula is empty".into(),
        });
    }
    let expr = Expr::parse(&out).map_err(|e| Error::Property {
        text: property.into(),
        message: format!("state formula `{}`: {e}", text.trim()),
    })?;
    Ok(StateFormula { expr })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_usual_properties_parse() {
        let p = Property::parse(r#"Pmax=? [F "goal"]"#).unwrap();
        assert_eq!(p.direction, Some(Direction::Max));
        assert_eq!(
            p.query,
            Query::Reach(StateFormula {
                expr: Expr::param("goal")
            })
        );
        let p = Property::parse(r#"R{"cost"}min=? [F #P3 = 1 & !"bad"]"#).unwrap();
        assert_eq!(p.reward_name(), Some("cost"));
        let Query::Reward(_, phi) = &p.query else { panic!() };
        assert_eq!(phi.expr.to_string(), "#P3 = 1 and not bad");
        let p = Property::parse(r#"LRAmax=? [ "up" ]"#).unwrap();
        assert!(matches!(p.query, Query::Lra(_)));
        let p = Property::parse(r#"R{"done"}max=? [ LRA ]"#).unwrap();
        assert_eq!(p.query, Query::RewardLra(Some("done".into())));
        let p = Property::parse(r#""name": P=? [F "a" | "b"]"#).unwrap();
        assert_eq!(p.direction, None);
        let p = Property::parse("Tmin=? [F #P1 != 0 && #P2 >= 1]").unwrap();
        assert!(matches!(p.query, Query::Time(_)));
    }

    #[test]
    fn unsupported_and_malformed_properties_are_explained() {
        for (text, says) in [
            (r#"P>=0.5 [F "a"]"#, "bounds"),
            (r#"Pmax=? [F<=10 "a"]"#, "bounds"),
            (r#"Pmax=? [G "a"]"#, "eventually"),
            (r#"Pmax=? [F "a""#, "closed"),
            (r#"Qmax=? [F "a"]"#, "expected P"),
            (r#"Pmax=? [F ]"#, "empty"),
            (r#"Pmax=? [F #P1 = ]"#, "state formula"),
            (r#"R{cost}min=? [F "a"]"#, "quoted"),
            (r#"Pmax [F "a"]"#, "=?"),
        ] {
            let err = Property::parse(text).unwrap_err().to_string();
            assert!(err.contains(says), "{text}: {err}");
        }
    }
}
