//! Expressions: rates, weights, markings and multiplicities written over named
//! parameters, and measures written over token counts.
//!
//! One small language serves both:
//!
//! ```text
//! expr  := or
//! or    := and  (("or" | "||") and)*
//! and   := not  (("and" | "&&") not)*
//! not   := ("not" | "!") not | cmp
//! cmp   := sum  (("=" | "==" | "!=" | "<" | "<=" | ">" | ">=") sum)?
//! sum   := prod (("+" | "-") prod)*
//! prod  := unary (("*" | "/") unary)*
//! unary := "-" unary | atom
//! atom  := NUMBER | "#" NAME | NAME | FUNC "(" expr ("," expr)* ")" | "(" expr ")"
//! NAME  := [A-Za-z_][A-Za-z0-9_.]* | '"' any text '"'
//! FUNC  := "min" | "max" | "abs" | "floor" | "ceil"
//! ```
//!
//! `#P` is the number of tokens in place `P` (GreatSPN's notation); a bare
//! name is a parameter. Comparisons and logic give 1 (true) or 0 (false), so
//! `P{#P1 = 1 and #P7 = 1}` is written `#P1 = 1 and #P7 = 1`, and its mean
//! over the steady state is its probability.

use std::fmt;

use crate::error::{Error, Result};

/// A binary operator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BinOp {
    /// `+`
    Add,
    /// `-`
    Sub,
    /// `*`
    Mul,
    /// `/`
    Div,
    /// `=` or `==`
    Eq,
    /// `!=`
    Ne,
    /// `<`
    Lt,
    /// `<=`
    Le,
    /// `>`
    Gt,
    /// `>=`
    Ge,
    /// `and`
    And,
    /// `or`
    Or,
}

impl BinOp {
    fn symbol(self) -> &'static str {
        match self {
            BinOp::Add => "+",
            BinOp::Sub => "-",
            BinOp::Mul => "*",
            BinOp::Div => "/",
            BinOp::Eq => "=",
            BinOp::Ne => "!=",
            BinOp::Lt => "<",
            BinOp::Le => "<=",
            BinOp::Gt => ">",
            BinOp::Ge => ">=",
            BinOp::And => "and",
            BinOp::Or => "or",
        }
    }

    /// Binding strength: larger binds tighter.
    fn precedence(self) -> u8 {
        match self {
            BinOp::Or => 1,
            BinOp::And => 2,
            BinOp::Eq | BinOp::Ne | BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge => 4,
            BinOp::Add | BinOp::Sub => 5,
            BinOp::Mul | BinOp::Div => 6,
        }
    }

    fn apply(self, a: f64, b: f64) -> f64 {
        let truth = |c: bool| if c { 1.0 } else { 0.0 };
        match self {
            BinOp::Add => a + b,
            BinOp::Sub => a - b,
            BinOp::Mul => a * b,
            BinOp::Div => a / b,
            BinOp::Eq => truth(a == b),
            BinOp::Ne => truth(a != b),
            BinOp::Lt => truth(a < b),
            BinOp::Le => truth(a <= b),
            BinOp::Gt => truth(a > b),
            BinOp::Ge => truth(a >= b),
            BinOp::And => truth(a != 0.0 && b != 0.0),
            BinOp::Or => truth(a != 0.0 || b != 0.0),
        }
    }
}

/// A built-in function.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Func {
    /// Smallest argument.
    Min,
    /// Largest argument.
    Max,
    /// Absolute value.
    Abs,
    /// Round down.
    Floor,
    /// Round up.
    Ceil,
}

impl Func {
    fn name(self) -> &'static str {
        match self {
            Func::Min => "min",
            Func::Max => "max",
            Func::Abs => "abs",
            Func::Floor => "floor",
            Func::Ceil => "ceil",
        }
    }

    fn from_name(name: &str) -> Option<Func> {
        Some(match name {
            "min" => Func::Min,
            "max" => Func::Max,
            "abs" => Func::Abs,
            "floor" => Func::Floor,
            "ceil" => Func::Ceil,
            _ => return None,
        })
    }

    fn arity_ok(self, n: usize) -> bool {
        match self {
            Func::Min | Func::Max => n >= 1,
            Func::Abs | Func::Floor | Func::Ceil => n == 1,
        }
    }

    fn apply(self, args: &[f64]) -> f64 {
        match self {
            Func::Min => args.iter().copied().fold(f64::INFINITY, f64::min),
            Func::Max => args.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            Func::Abs => args[0].abs(),
            Func::Floor => args[0].floor(),
            Func::Ceil => args[0].ceil(),
        }
    }
}

/// An expression tree.
#[derive(Debug, Clone, PartialEq)]
pub enum Expr {
    /// A number.
    Num(f64),
    /// A named parameter.
    Param(String),
    /// The token count of a place, `#P`.
    Tokens(String),
    /// Arithmetic negation.
    Neg(Box<Expr>),
    /// Logical negation.
    Not(Box<Expr>),
    /// A binary operation.
    Binary(BinOp, Box<Expr>, Box<Expr>),
    /// A function call.
    Call(Func, Vec<Expr>),
}

impl From<f64> for Expr {
    fn from(v: f64) -> Self {
        Expr::Num(v)
    }
}

impl From<u32> for Expr {
    fn from(v: u32) -> Self {
        Expr::Num(f64::from(v))
    }
}

impl Expr {
    /// Parses an expression.
    ///
    /// ```
    /// use petri::Expr;
    /// let e = Expr::parse("#P1 = 1 and #P7 >= 1").unwrap();
    /// assert_eq!(e.to_string(), "#P1 = 1 and #P7 >= 1");
    /// ```
    pub fn parse(text: &str) -> Result<Expr> {
        let mut p = Parser {
            text,
            chars: text.char_indices().collect(),
            pos: 0,
            depth: 0,
        };
        let e = p.or()?;
        p.skip_ws();
        if p.pos < p.chars.len() {
            return Err(p.error("unexpected text after the end of the expression"));
        }
        Ok(e)
    }

    /// A parameter reference.
    pub fn param(name: impl Into<String>) -> Expr {
        Expr::Param(name.into())
    }

    /// The number, if the expression is a plain number.
    pub fn as_number(&self) -> Option<f64> {
        match self {
            Expr::Num(v) => Some(*v),
            _ => None,
        }
    }

    /// Calls `f` on every parameter name the expression uses.
    pub fn for_each_param(&self, f: &mut impl FnMut(&str)) {
        self.visit(&mut |e| {
            if let Expr::Param(n) = e {
                f(n)
            }
        });
    }

    /// The expression with every parameter `n` for which `f(n)` gives an
    /// expression replaced by it (labels by their conditions, say).
    pub fn substitute(&self, f: &dyn Fn(&str) -> Option<Expr>) -> Expr {
        match self {
            Expr::Param(n) => f(n).unwrap_or_else(|| self.clone()),
            Expr::Num(_) | Expr::Tokens(_) => self.clone(),
            Expr::Neg(a) => Expr::Neg(Box::new(a.substitute(f))),
            Expr::Not(a) => Expr::Not(Box::new(a.substitute(f))),
            Expr::Binary(op, a, b) => Expr::Binary(*op, Box::new(a.substitute(f)), Box::new(b.substitute(f))),
            Expr::Call(func, args) => Expr::Call(*func, args.iter().map(|a| a.substitute(f)).collect()),
        }
    }

    /// Whether the expression reads token counts.
    pub fn uses_tokens(&self) -> bool {
        let mut found = false;
        self.visit(&mut |e| found |= matches!(e, Expr::Tokens(_)));
        found
    }

    fn visit(&self, f: &mut impl FnMut(&Expr)) {
        f(self);
        match self {
            Expr::Num(_) | Expr::Param(_) | Expr::Tokens(_) => {}
            Expr::Neg(a) | Expr::Not(a) => a.visit(f),
            Expr::Binary(_, a, b) => {
                a.visit(f);
                b.visit(f);
            }
            Expr::Call(_, args) => args.iter().for_each(|a| a.visit(f)),
        }
    }

    /// Evaluates with `param` giving parameter values and `tokens` token
    /// counts; either may refuse by returning an error message.
    pub fn eval_with(
        &self,
        param: &mut dyn FnMut(&str) -> std::result::Result<f64, String>,
        tokens: &mut dyn FnMut(&str) -> std::result::Result<f64, String>,
    ) -> std::result::Result<f64, String> {
        Ok(match self {
            Expr::Num(v) => *v,
            Expr::Param(n) => param(n)?,
            Expr::Tokens(n) => tokens(n)?,
            Expr::Neg(a) => -a.eval_with(param, tokens)?,
            Expr::Not(a) => {
                if a.eval_with(param, tokens)? == 0.0 {
                    1.0
                } else {
                    0.0
                }
            }
            Expr::Binary(op, a, b) => op.apply(a.eval_with(param, tokens)?, b.eval_with(param, tokens)?),
            Expr::Call(func, args) => {
                let vals = args
                    .iter()
                    .map(|a| a.eval_with(param, tokens))
                    .collect::<std::result::Result<Vec<_>, _>>()?;
                func.apply(&vals)
            }
        })
    }

    /// Evaluates an expression that may only use parameters. `context` names
    /// what the value is for, for the error message.
    pub fn eval_params(&self, lookup: &dyn Fn(&str) -> Option<f64>, context: &str) -> Result<f64> {
        self.eval_with(
            &mut |n| lookup(n).ok_or_else(|| format!("parameter `{n}` has no value")),
            &mut |p| {
                Err(format!(
                    "token counts (#{p}) cannot be used here: marking-dependent values are not supported"
                ))
            },
        )
        .map_err(|message| Error::Eval {
            text: self.to_string(),
            context: context.to_string(),
            message,
        })
    }

    /// Compiles the expression for fast evaluation on markings: place names
    /// become indices (via `place_index`), parameters become their values.
    pub fn compile(
        &self,
        place_index: &dyn Fn(&str) -> Option<usize>,
        param: &dyn Fn(&str) -> Option<f64>,
    ) -> Result<CompiledExpr> {
        let mut code = Vec::new();
        self.emit(place_index, param, &mut code)?;
        Ok(CompiledExpr { code })
    }

    fn emit(
        &self,
        place_index: &dyn Fn(&str) -> Option<usize>,
        param: &dyn Fn(&str) -> Option<f64>,
        code: &mut Vec<Op>,
    ) -> Result<()> {
        let err = |message: String| Error::Eval {
            text: self.to_string(),
            context: "a measure".into(),
            message,
        };
        match self {
            Expr::Num(v) => code.push(Op::Const(*v)),
            Expr::Param(n) => code.push(Op::Const(param(n).ok_or_else(|| {
                err(format!(
                    "unknown parameter `{n}` (a place's tokens are written #{n})"
                ))
            })?)),
            Expr::Tokens(n) => code.push(Op::Tokens(
                place_index(n).ok_or_else(|| err(format!("unknown place `{n}`")))?,
            )),
            Expr::Neg(a) => {
                a.emit(place_index, param, code)?;
                code.push(Op::Neg);
            }
            Expr::Not(a) => {
                a.emit(place_index, param, code)?;
                code.push(Op::Not);
            }
            Expr::Binary(op, a, b) => {
                a.emit(place_index, param, code)?;
                b.emit(place_index, param, code)?;
                code.push(Op::Bin(*op));
            }
            Expr::Call(f, args) => {
                for a in args {
                    a.emit(place_index, param, code)?;
                }
                code.push(Op::Call(*f, args.len()));
            }
        }
        Ok(())
    }

    fn fmt_prec(&self, f: &mut fmt::Formatter<'_>, parent: u8) -> fmt::Result {
        match self {
            Expr::Num(v) => write!(f, "{}", fmt_number(*v)),
            Expr::Param(n) => write_name(f, n),
            Expr::Tokens(n) => {
                f.write_str("#")?;
                write_name(f, n)
            }
            Expr::Neg(a) => {
                f.write_str("-")?;
                a.fmt_prec(f, 7)
            }
            Expr::Not(a) => {
                // `not` binds looser than comparisons and arithmetic.
                let paren = parent > 3;
                if paren {
                    f.write_str("(")?;
                }
                f.write_str("not ")?;
                a.fmt_prec(f, 3)?;
                if paren {
                    f.write_str(")")?;
                }
                Ok(())
            }
            Expr::Binary(op, a, b) => {
                let p = op.precedence();
                let paren = p < parent;
                if paren {
                    f.write_str("(")?;
                }
                // Comparisons do not chain: a comparison operand needs parentheses.
                a.fmt_prec(f, if p == 4 { p + 1 } else { p })?;
                write!(f, " {} ", op.symbol())?;
                // Left-associative: the right operand needs parentheses at equal precedence.
                b.fmt_prec(f, p + 1)?;
                if paren {
                    f.write_str(")")?;
                }
                Ok(())
            }
            Expr::Call(func, args) => {
                write!(f, "{}(", func.name())?;
                for (i, a) in args.iter().enumerate() {
                    if i > 0 {
                        f.write_str(", ")?;
                    }
                    a.fmt_prec(f, 0)?;
                }
                f.write_str(")")
            }
        }
    }
}

/// Formats a number so that it parses back to the same `f64`.
pub fn fmt_number(v: f64) -> String {
    if v.is_finite() && v == v.trunc() && v.abs() < 1e15 {
        format!("{}", v as i64)
    } else {
        format!("{v:?}")
    }
}

fn is_infinity(n: &str) -> bool {
    matches!(n, "inf" | "infinity" | "Infinity")
}

/// Whether a name can be written without quotes. Names containing `"` cannot
/// be written in an expression at all (no escape exists).
fn is_plain_name(n: &str) -> bool {
    let mut chars = n.chars();
    matches!(chars.next(), Some(c) if c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '.')
        && !matches!(n, "and" | "or" | "not")
        && !is_infinity(n)
        && Func::from_name(n).is_none()
}

fn write_name(f: &mut fmt::Formatter<'_>, n: &str) -> fmt::Result {
    if is_plain_name(n) {
        f.write_str(n)
    } else {
        write!(f, "\"{n}\"")
    }
}

impl fmt::Display for Expr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.fmt_prec(f, 0)
    }
}

#[derive(Debug, Clone, Copy)]
enum Op {
    Const(f64),
    Tokens(usize),
    Neg,
    Not,
    Bin(BinOp),
    Call(Func, usize),
}

/// An expression compiled to a small stack program over a marking.
#[derive(Debug, Clone)]
pub struct CompiledExpr {
    code: Vec<Op>,
}

impl CompiledExpr {
    /// Evaluates on a marking (token count per place index).
    pub fn eval(&self, marking: &[u32], stack: &mut Vec<f64>) -> f64 {
        stack.clear();
        for op in &self.code {
            match *op {
                Op::Const(v) => stack.push(v),
                Op::Tokens(p) => stack.push(marking.get(p).map_or(0.0, |&k| f64::from(k))),
                Op::Neg => {
                    let a = stack.pop().unwrap_or(0.0);
                    stack.push(-a);
                }
                Op::Not => {
                    let a = stack.pop().unwrap_or(0.0);
                    stack.push(if a == 0.0 { 1.0 } else { 0.0 });
                }
                Op::Bin(op) => {
                    let b = stack.pop().unwrap_or(0.0);
                    let a = stack.pop().unwrap_or(0.0);
                    stack.push(op.apply(a, b));
                }
                Op::Call(f, n) => {
                    let at = stack.len().saturating_sub(n);
                    let v = f.apply(&stack[at..]);
                    stack.truncate(at);
                    stack.push(v);
                }
            }
        }
        stack.pop().unwrap_or(0.0)
    }
}

struct Parser<'a> {
    text: &'a str,
    chars: Vec<(usize, char)>,
    pos: usize,
    depth: usize,
}

/// Deepest nesting (parentheses, unary operators, function calls) an
/// expression may have: the parser is recursive, and no input may exhaust
/// the stack.
pub const MAX_DEPTH: usize = 64;

impl Parser<'_> {
    /// Enters one level of nesting, failing beyond [`MAX_DEPTH`].
    fn nest(&mut self) -> Result<()> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(self.error(&format!(
                "the expression is nested more than {MAX_DEPTH} levels deep"
            )));
        }
        Ok(())
    }

    fn error(&self, message: &str) -> Error {
        Error::Expr {
            text: self.text.to_string(),
            position: self.pos + 1,
            message: message.to_string(),
        }
    }

    fn peek(&self) -> Option<char> {
        self.chars.get(self.pos).map(|&(_, c)| c)
    }

    fn skip_ws(&mut self) {
        while matches!(self.peek(), Some(c) if c.is_whitespace()) {
            self.pos += 1;
        }
    }

    /// Consumes `s` if it comes next (after spaces). Words must not be
    /// followed by a name character.
    fn eat(&mut self, s: &str) -> bool {
        self.skip_ws();
        let n = s.chars().count();
        if self.pos + n > self.chars.len() {
            return false;
        }
        if !self.chars[self.pos..self.pos + n]
            .iter()
            .map(|&(_, c)| c)
            .eq(s.chars())
        {
            return false;
        }
        let is_word = s.chars().all(|c| c.is_ascii_alphabetic());
        if is_word
            && matches!(self.chars.get(self.pos + n), Some(&(_, c)) if c.is_ascii_alphanumeric() || c == '_')
        {
            return false;
        }
        self.pos += n;
        true
    }

    fn or(&mut self) -> Result<Expr> {
        let mut e = self.and()?;
        while self.eat("||") || self.eat("or") {
            let r = self.and()?;
            e = Expr::Binary(BinOp::Or, Box::new(e), Box::new(r));
        }
        Ok(e)
    }

    fn and(&mut self) -> Result<Expr> {
        let mut e = self.not()?;
        while self.eat("&&") || self.eat("and") {
            let r = self.not()?;
            e = Expr::Binary(BinOp::And, Box::new(e), Box::new(r));
        }
        Ok(e)
    }

    fn not(&mut self) -> Result<Expr> {
        self.skip_ws();
        if self.eat("not")
            || (self.peek() == Some('!')
                && self.chars.get(self.pos + 1).map(|c| c.1) != Some('=')
                && self.eat("!"))
        {
            self.nest()?;
            let inner = self.not()?;
            self.depth -= 1;
            return Ok(Expr::Not(Box::new(inner)));
        }
        self.cmp()
    }

    fn cmp(&mut self) -> Result<Expr> {
        let a = self.sum()?;
        let op = if self.eat("==") || self.eat("=") {
            BinOp::Eq
        } else if self.eat("!=") {
            BinOp::Ne
        } else if self.eat("<=") {
            BinOp::Le
        } else if self.eat(">=") {
            BinOp::Ge
        } else if self.eat("<") {
            BinOp::Lt
        } else if self.eat(">") {
            BinOp::Gt
        } else {
            return Ok(a);
        };
        let b = self.sum()?;
        Ok(Expr::Binary(op, Box::new(a), Box::new(b)))
    }

    fn sum(&mut self) -> Result<Expr> {
        let mut e = self.prod()?;
        loop {
            let op = if self.eat("+") {
                BinOp::Add
            } else if self.eat("-") {
                BinOp::Sub
            } else {
                return Ok(e);
            };
            let r = self.prod()?;
            e = Expr::Binary(op, Box::new(e), Box::new(r));
        }
    }

    fn prod(&mut self) -> Result<Expr> {
        let mut e = self.unary()?;
        loop {
            let op = if self.eat("*") {
                BinOp::Mul
            } else if self.eat("/") {
                BinOp::Div
            } else {
                return Ok(e);
            };
            let r = self.unary()?;
            e = Expr::Binary(op, Box::new(e), Box::new(r));
        }
    }

    fn unary(&mut self) -> Result<Expr> {
        if self.eat("-") {
            self.nest()?;
            let a = self.unary()?;
            self.depth -= 1;
            return Ok(match a {
                Expr::Num(v) => Expr::Num(-v),
                a => Expr::Neg(Box::new(a)),
            });
        }
        if self.eat("+") {
            self.nest()?;
            let a = self.unary();
            self.depth -= 1;
            return a;
        }
        self.atom()
    }

    fn name(&mut self) -> Result<String> {
        self.skip_ws();
        if self.peek() == Some('"') {
            self.pos += 1;
            let start = self.pos;
            while matches!(self.peek(), Some(c) if c != '"') {
                self.pos += 1;
            }
            if self.peek() != Some('"') {
                return Err(self.error("unterminated quoted name"));
            }
            let name: String = self.chars[start..self.pos].iter().map(|c| c.1).collect();
            self.pos += 1;
            return Ok(name);
        }
        let start = self.pos;
        match self.peek() {
            Some(c) if c.is_ascii_alphabetic() || c == '_' => {}
            _ => return Err(self.error("expected a name")),
        }
        while matches!(self.peek(), Some(c) if c.is_ascii_alphanumeric() || c == '_' || c == '.') {
            self.pos += 1;
        }
        Ok(self.chars[start..self.pos].iter().map(|c| c.1).collect())
    }

    fn atom(&mut self) -> Result<Expr> {
        self.skip_ws();
        match self.peek() {
            None => Err(self.error("unexpected end of the expression")),
            Some('(') => {
                self.pos += 1;
                self.nest()?;
                let e = self.or()?;
                if !self.eat(")") {
                    return Err(self.error("expected `)`"));
                }
                self.depth -= 1;
                Ok(e)
            }
            Some('#') => {
                self.pos += 1;
                Ok(Expr::Tokens(self.name()?))
            }
            Some(c) if c.is_ascii_digit() || c == '.' => self.number(),
            Some(c) if c.is_ascii_alphabetic() || c == '_' || c == '"' => {
                let start = self.pos;
                let quoted = c == '"';
                let n = self.name()?;
                if !quoted && matches!(n.as_str(), "and" | "or" | "not") {
                    self.pos = start;
                    return Err(self.error("expected a value before this operator"));
                }
                if self.eat("(") {
                    let Some(func) = Func::from_name(&n) else {
                        self.pos = start;
                        return Err(self.error(&format!(
                            "unknown function `{n}` (known: min, max, abs, floor, ceil)"
                        )));
                    };
                    self.nest()?;
                    let mut args = vec![self.or()?];
                    while self.eat(",") {
                        args.push(self.or()?);
                    }
                    if !self.eat(")") {
                        return Err(self.error("expected `)` or `,` in the argument list"));
                    }
                    if !func.arity_ok(args.len()) {
                        self.pos = start;
                        return Err(self.error(&format!("wrong number of arguments for `{n}`")));
                    }
                    self.depth -= 1;
                    return Ok(Expr::Call(func, args));
                }
                if !quoted && is_infinity(&n) {
                    return Ok(Expr::Num(f64::INFINITY));
                }
                Ok(Expr::Param(n))
            }
            Some(_) => Err(self.error("expected a number, a name, #place or `(`")),
        }
    }

    fn number(&mut self) -> Result<Expr> {
        let start = self.pos;
        let digits = |p: &mut Self| {
            while matches!(p.peek(), Some(c) if c.is_ascii_digit()) {
                p.pos += 1;
            }
        };
        digits(self);
        if self.peek() == Some('.') {
            self.pos += 1;
            digits(self);
        }
        if matches!(self.peek(), Some('e' | 'E')) {
            let save = self.pos;
            self.pos += 1;
            if matches!(self.peek(), Some('+' | '-')) {
                self.pos += 1;
            }
            if matches!(self.peek(), Some(c) if c.is_ascii_digit()) {
                digits(self);
            } else {
                self.pos = save;
            }
        }
        let s: String = self.chars[start..self.pos].iter().map(|c| c.1).collect();
        s.parse::<f64>().map(Expr::Num).map_err(|_| {
            self.pos = start;
            self.error(&format!("`{s}` is not a number"))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn eval(s: &str) -> f64 {
        Expr::parse(s)
            .unwrap()
            .eval_params(&|n| (n == "x").then_some(2.0), "test")
            .unwrap()
    }

    #[test]
    fn arithmetic_precedence_and_associativity() {
        assert_eq!(eval("1 + 2 * 3"), 7.0);
        assert_eq!(eval("(1 + 2) * 3"), 9.0);
        assert_eq!(eval("8 - 3 - 2"), 3.0);
        assert_eq!(eval("8 / 4 / 2"), 1.0);
        assert_eq!(eval("-x * 3"), -6.0);
        assert_eq!(eval("1e-3 * 1000"), 1.0);
        assert_eq!(eval("1 - x"), -1.0);
        assert_eq!(eval("max(1, x, 0.5) + min(4, 3)"), 5.0);
    }

    #[test]
    fn logic() {
        assert_eq!(eval("1 = 1 and 2 > 1"), 1.0);
        assert_eq!(eval("1 = 2 or not 0"), 1.0);
        assert_eq!(eval("!(x != 2)"), 1.0);
        assert_eq!(eval("x >= 3 || x <= 1"), 0.0);
    }

    #[test]
    fn display_round_trips() {
        for s in [
            "#P1 = 1 and #P7 = 1",
            "1 - p",
            "a - (b - c)",
            "(a + b) * c",
            "not (#A > 0 or #B > 0)",
            "#\"odd name\" + 0.5",
            "-x / 2",
            "1.5e-7 * lambda1",
            "min(#P, 3) * mu",
            "(a < b) < c",
            "(not a) = b",
            "(not a) * b",
            "\"inf\" + inf",
            "\"min\" * 2",
        ] {
            let e = Expr::parse(s).unwrap();
            let again = Expr::parse(&e.to_string()).unwrap();
            assert_eq!(e, again, "{s} -> {e}");
        }
    }

    #[test]
    fn deep_nesting_is_an_error_not_a_stack_overflow() {
        for deep in [
            "(".repeat(5000) + "1" + &")".repeat(5000),
            "-".repeat(5000) + "1",
            "not ".repeat(5000) + "1",
        ] {
            let err = Expr::parse(&deep).unwrap_err().to_string();
            assert!(err.contains("nested"), "{err}");
        }
        let ok = "(".repeat(MAX_DEPTH - 1) + "1" + &")".repeat(MAX_DEPTH - 1);
        assert_eq!(Expr::parse(&ok).unwrap(), Expr::Num(1.0));
    }

    #[test]
    fn errors_name_the_position() {
        let err = Expr::parse("1 + * 2").unwrap_err().to_string();
        assert!(err.contains("character 5"), "{err}");
        assert!(Expr::parse("(1 + 2").is_err());
        assert!(Expr::parse("foo(1)").is_err());
        assert!(Expr::parse("1 2").is_err());
        assert!(Expr::parse("").is_err());
        assert!(Expr::parse("#").is_err());
    }

    #[test]
    fn tokens_are_refused_where_only_parameters_are_allowed() {
        let e = Expr::parse("#P * 2").unwrap();
        let err = e.eval_params(&|_| None, "the rate of `t`").unwrap_err();
        assert!(err.to_string().contains("marking-dependent"));
    }

    #[test]
    fn compiled_expression_reads_markings() {
        let e = Expr::parse("#a = 1 and #b >= 2 * k").unwrap();
        let c = e
            .compile(
                &|n| match n {
                    "a" => Some(0),
                    "b" => Some(1),
                    _ => None,
                },
                &|n| (n == "k").then_some(1.0),
            )
            .unwrap();
        let mut st = Vec::new();
        assert_eq!(c.eval(&[1, 2], &mut st), 1.0);
        assert_eq!(c.eval(&[1, 1], &mut st), 0.0);
        assert!(Expr::parse("#zz").unwrap().compile(&|_| None, &|_| None).is_err());
    }
}
