//! A tiny expression language for custom combine functions on the command line:
//! `--combine 'expr:max(px, nx) * 0.5 + mean(py, ny, pz, nz) * 0.5'`.
//!
//! Every value is an RGBA vec4; numbers are splatted to all four channels.
//! - variables `px nx py ny pz nz`: the premultiplied RGBA seen from +X, −X, +Y, −Y, +Z, −Z;
//! - `+ - * /` (per channel, usual precedence, left-associative), unary `-`, parentheses;
//! - channel access `v.r v.g v.b v.a` (also `.x .y .z .w`) gives that channel splatted;
//! - functions: `min(..)`, `max(..)`, `mean(..)`, `sum(..)` (one or more arguments, per
//!   channel), `abs(v)`, `clamp(v, lo, hi)`, `mix(a, b, t)` (= a + (b − a)·t),
//!   `rgba(r, g, b, a)` (channel 0 of r, 1 of g, 2 of b, 3 of a — with splatted scalars,
//!   just the four values).
//!
//! The result is clamped to a valid premultiplied colour
//! ([`super::quantize::clamp_premultiplied`]): NaN → 0, `0 ≤ a ≤ 1`, `0 ≤ rgb ≤ a`.
//! The source is parsed once into an AST and evaluated per voxel. Errors give the 1-based
//! column (in characters) of the offending token. An expression is at most
//! [`MAX_TOKENS`] tokens long and nested at most [`MAX_DEPTH`] levels deep, which bounds the
//! tree's size and height (the parser and evaluator recurse over it).

use std::fmt;

use glam::Vec4;

/// A parse error at `column` (1-based, in characters).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ExprError {
    pub column: usize,
    pub message: String,
    /// The expression is well-formed as far as it was read but over a size limit
    /// ([`MAX_TOKENS`], [`MAX_DEPTH`]) rather than unparsable.
    pub too_large: bool,
}

impl fmt::Display for ExprError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "column {}: {}", self.column, self.message)
    }
}

impl std::error::Error for ExprError {}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Func {
    Min,
    Max,
    Mean,
    Sum,
    Abs,
    Clamp,
    Mix,
    Rgba,
}

#[derive(Clone, Debug, PartialEq)]
enum Node {
    Num(f32),
    Var(usize),
    Neg(Box<Node>),
    Bin(u8, Box<Node>, Box<Node>),
    Chan(Box<Node>, usize),
    Call(Func, Vec<Node>),
}

/// A parsed combine expression.
#[derive(Clone, Debug, PartialEq)]
pub struct Expr {
    src: String,
    root: Node,
}

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Num(f32),
    Ident(String),
    Sym(char),
    End,
}

fn lex(src: &str) -> Result<Vec<(Tok, usize)>, ExprError> {
    let chars: Vec<char> = src.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let col = i + 1;
        if c.is_whitespace() {
            i += 1;
        } else if c.is_ascii_digit()
            || (c == '.' && chars.get(i + 1).is_some_and(|d| d.is_ascii_digit()))
        {
            let start = i;
            while i < chars.len() && (chars[i].is_ascii_digit() || chars[i] == '.') {
                i += 1;
            }
            if i < chars.len() && (chars[i] == 'e' || chars[i] == 'E') {
                let mut j = i + 1;
                if j < chars.len() && (chars[j] == '+' || chars[j] == '-') {
                    j += 1;
                }
                if j < chars.len() && chars[j].is_ascii_digit() {
                    i = j;
                    while i < chars.len() && chars[i].is_ascii_digit() {
                        i += 1;
                    }
                }
            }
            let text: String = chars[start..i].iter().collect();
            let v = text.parse::<f32>().map_err(|_| ExprError {
                column: col,
                message: format!("bad number '{text}'"),
                too_large: false,
            })?;
            out.push((Tok::Num(v), col));
        } else if c.is_ascii_alphabetic() || c == '_' {
            let start = i;
            while i < chars.len() && (chars[i].is_ascii_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            out.push((Tok::Ident(chars[start..i].iter().collect()), col));
        } else if "+-*/(),.".contains(c) {
            out.push((Tok::Sym(c), col));
            i += 1;
        } else {
            return Err(ExprError {
                column: col,
                message: format!("unexpected character '{c}'"),
                too_large: false,
            });
        }
    }
    out.push((Tok::End, chars.len() + 1));
    Ok(out)
}

struct Parser {
    toks: Vec<(Tok, usize)>,
    pos: usize,
    depth: usize,
}

/// Deepest nesting accepted (keeps the recursive parser and evaluator off the stack limit).
pub const MAX_DEPTH: usize = 64;

/// Most tokens accepted. Every tree node consumes at least one token, so this bounds the
/// node count and the height of a long flat chain (`px+px+…` is left-deep), which the
/// nesting limit does not see; the evaluator and `Drop` recurse over that height.
pub const MAX_TOKENS: usize = 1024;

fn describe(t: &Tok) -> String {
    match t {
        Tok::Num(v) => format!("number {v}"),
        Tok::Ident(s) => format!("'{s}'"),
        Tok::Sym(c) => format!("'{c}'"),
        Tok::End => "end of expression".into(),
    }
}

impl Parser {
    fn peek(&self) -> &Tok {
        &self.toks[self.pos].0
    }
    fn col(&self) -> usize {
        self.toks[self.pos].1
    }
    fn err<T>(&self, message: String) -> Result<T, ExprError> {
        Err(ExprError {
            column: self.col(),
            message,
            too_large: false,
        })
    }
    fn expect(&mut self, c: char) -> Result<(), ExprError> {
        if *self.peek() == Tok::Sym(c) {
            self.pos += 1;
            Ok(())
        } else {
            self.err(format!("expected '{c}', found {}", describe(self.peek())))
        }
    }
    fn expr(&mut self) -> Result<Node, ExprError> {
        let mut lhs = self.term()?;
        while let Tok::Sym(op @ ('+' | '-')) = *self.peek() {
            self.pos += 1;
            lhs = Node::Bin(op as u8, Box::new(lhs), Box::new(self.term()?));
        }
        Ok(lhs)
    }
    fn term(&mut self) -> Result<Node, ExprError> {
        let mut lhs = self.unary()?;
        while let Tok::Sym(op @ ('*' | '/')) = *self.peek() {
            self.pos += 1;
            lhs = Node::Bin(op as u8, Box::new(lhs), Box::new(self.unary()?));
        }
        Ok(lhs)
    }
    fn unary(&mut self) -> Result<Node, ExprError> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            let mut e = self
                .err::<()>(format!("expression nested deeper than {MAX_DEPTH} levels"))
                .unwrap_err();
            e.too_large = true;
            return Err(e);
        }
        let r = self.unary_inner();
        self.depth -= 1;
        r
    }
    fn unary_inner(&mut self) -> Result<Node, ExprError> {
        if *self.peek() == Tok::Sym('-') {
            self.pos += 1;
            return Ok(Node::Neg(Box::new(self.unary()?)));
        }
        let mut node = self.primary()?;
        while *self.peek() == Tok::Sym('.') {
            self.pos += 1;
            let ch = match self.peek() {
                Tok::Ident(s) => match s.as_str() {
                    "r" | "x" => 0,
                    "g" | "y" => 1,
                    "b" | "z" => 2,
                    "a" | "w" => 3,
                    _ => {
                        return self.err(format!(
                            "unknown channel '{s}': expected r, g, b, a (or x, y, z, w)"
                        ))
                    }
                },
                t => {
                    return self.err(format!(
                        "expected a channel (r, g, b, a) after '.', found {}",
                        describe(t)
                    ))
                }
            };
            self.pos += 1;
            node = Node::Chan(Box::new(node), ch);
        }
        Ok(node)
    }
    fn primary(&mut self) -> Result<Node, ExprError> {
        let col = self.col();
        match self.peek().clone() {
            Tok::Num(v) => {
                self.pos += 1;
                Ok(Node::Num(v))
            }
            Tok::Sym('(') => {
                self.pos += 1;
                let e = self.expr()?;
                self.expect(')')?;
                Ok(e)
            }
            Tok::Ident(name) => {
                self.pos += 1;
                const VARS: [&str; 6] = ["px", "nx", "py", "ny", "pz", "nz"];
                if let Some(i) = VARS.iter().position(|v| *v == name) {
                    return Ok(Node::Var(i));
                }
                let (f, arity): (Func, Option<usize>) = match name.as_str() {
                    "min" => (Func::Min, None),
                    "max" => (Func::Max, None),
                    "mean" => (Func::Mean, None),
                    "sum" => (Func::Sum, None),
                    "abs" => (Func::Abs, Some(1)),
                    "clamp" => (Func::Clamp, Some(3)),
                    "mix" => (Func::Mix, Some(3)),
                    "rgba" => (Func::Rgba, Some(4)),
                    _ => {
                        return Err(ExprError {
                            column: col,
                            message: format!(
                                "unknown name '{name}': variables are px nx py ny pz nz, functions min max mean sum abs clamp mix rgba"
                            ),
                            too_large: false,
                        })
                    }
                };
                if *self.peek() != Tok::Sym('(') {
                    return self.err(format!("expected '(' after function '{name}'"));
                }
                self.pos += 1;
                let mut args = vec![self.expr()?];
                while *self.peek() == Tok::Sym(',') {
                    self.pos += 1;
                    args.push(self.expr()?);
                }
                self.expect(')')?;
                if let Some(n) = arity {
                    if args.len() != n {
                        return Err(ExprError {
                            column: col,
                            message: format!("'{name}' takes {n} argument(s), got {}", args.len()),
                            too_large: false,
                        });
                    }
                }
                Ok(Node::Call(f, args))
            }
            t => self.err(format!("expected a value, found {}", describe(&t))),
        }
    }
}

fn eval(n: &Node, s: &[Vec4; 6]) -> Vec4 {
    match n {
        Node::Num(v) => Vec4::splat(*v),
        Node::Var(i) => s[*i],
        Node::Neg(a) => -eval(a, s),
        Node::Bin(op, a, b) => {
            let (a, b) = (eval(a, s), eval(b, s));
            match op {
                b'+' => a + b,
                b'-' => a - b,
                b'*' => a * b,
                _ => a / b,
            }
        }
        Node::Chan(a, c) => Vec4::splat(eval(a, s)[*c]),
        Node::Call(f, args) => {
            let mut vals = args.iter().map(|a| eval(a, s));
            match f {
                Func::Min => vals.reduce(Vec4::min).unwrap_or(Vec4::ZERO),
                Func::Max => vals.reduce(Vec4::max).unwrap_or(Vec4::ZERO),
                Func::Sum => vals.fold(Vec4::ZERO, |a, b| a + b),
                Func::Mean => vals.fold(Vec4::ZERO, |a, b| a + b) / args.len() as f32,
                Func::Abs => vals.next().unwrap_or(Vec4::ZERO).abs(),
                Func::Clamp => {
                    let v: Vec<Vec4> = vals.collect();
                    v[0].max(v[1]).min(v[2])
                }
                Func::Mix => {
                    let v: Vec<Vec4> = vals.collect();
                    v[0] + (v[1] - v[0]) * v[2]
                }
                Func::Rgba => {
                    let v: Vec<Vec4> = vals.collect();
                    Vec4::new(v[0].x, v[1].y, v[2].z, v[3].w)
                }
            }
        }
    }
}

impl Expr {
    /// Parses `src` (without the CLI's `expr:` prefix).
    pub fn parse(src: &str) -> Result<Expr, ExprError> {
        let mut p = Parser {
            toks: lex(src)?,
            pos: 0,
            depth: 0,
        };
        if p.toks.len() == 1 {
            return p.err("empty expression".into());
        }
        if p.toks.len() - 1 > MAX_TOKENS {
            return Err(ExprError {
                column: p.toks[MAX_TOKENS].1,
                message: format!(
                    "expression longer than {MAX_TOKENS} tokens ({} given)",
                    p.toks.len() - 1
                ),
                too_large: true,
            });
        }
        let root = p.expr()?;
        if *p.peek() != Tok::End {
            return p.err(format!(
                "unexpected {} after the end of the expression",
                describe(p.peek())
            ));
        }
        Ok(Expr {
            src: src.into(),
            root,
        })
    }

    /// The source text as given.
    pub fn source(&self) -> &str {
        &self.src
    }

    /// Evaluates without clamping.
    pub fn eval(&self, s: &[Vec4; 6]) -> Vec4 {
        eval(&self.root, s)
    }
}

impl std::str::FromStr for Expr {
    type Err = ExprError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Expr::parse(s)
    }
}
