//! Text form of abstract programs (paper Table 2), and its parser.
//!
//! ```text
//! abstract_program(fps=30, units=px, dims=2, unit_scale=1)
//! joints(head, left_wrist)
//! motion(duration=14) {
//!   head: start=(243.2, 171), mid=(213, 131), end=(251, 98.3)
//!   left_wrist: start=(…), mid=(…), end=(…)
//! }
//! for i in range(24) {
//!   motion(duration=sample({14: 3, 15: 1})) {
//!     head: Gaussian(mean=<(…), (…), (…)>, cov=[36 numbers, row-major])
//!     …
//!   }
//!   observed {            # optional: the recorded iterations
//!     iteration {
//!       motion(duration=14) { … }
//!     }
//!   }
//! }
//! ```
//!
//! Numbers are printed with the shortest representation that reads back to
//! the same `f64`, so `AbstractProgram::from_dsl(&p.to_dsl()) == p`. `#` starts a comment.

use std::fmt::Write;

use mp_concrete::lex::{self as shared, LexRules};

use crate::error::{AbstractError, Result};
use crate::model::{AbstractProgram, DetPrim, FreqDist, Gaussian, Loop, ProbPrim, Stmt};

/// Printing options.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PrintOptions {
    /// Decimal places; `None` prints exact (round-trip) numbers.
    pub precision: Option<usize>,
    /// Print covariance matrices (otherwise only their Frobenius norm as a comment).
    pub covariances: bool,
    /// Print the recorded iterations of loops.
    pub observed: bool,
}

impl Default for PrintOptions {
    fn default() -> Self {
        PrintOptions {
            precision: None,
            covariances: true,
            observed: true,
        }
    }
}

impl PrintOptions {
    /// A readable summary (2 decimals, no covariances, no recorded iterations); not for parsing back exactly.
    pub fn summary() -> Self {
        PrintOptions {
            precision: Some(2),
            covariances: false,
            observed: false,
        }
    }
}

fn num(x: f64, o: &PrintOptions) -> String {
    match o.precision {
        Some(p) => format!("{x:.p$}"),
        None => format!("{x:?}"),
    }
}

fn point(v: &[f64], o: &PrintOptions) -> String {
    let parts: Vec<String> = v.iter().map(|x| num(*x, o)).collect();
    format!("({})", parts.join(", "))
}

fn write_det(
    out: &mut String,
    p: &DetPrim,
    joints: &[String],
    dims: usize,
    indent: &str,
    o: &PrintOptions,
) {
    let _ = writeln!(out, "{indent}motion(duration={}) {{", p.duration);
    for (name, v) in joints.iter().zip(&p.points) {
        let _ = writeln!(
            out,
            "{indent}  {name}: start={}, mid={}, end={}",
            point(&v[..dims], o),
            point(&v[dims..2 * dims], o),
            point(&v[2 * dims..], o)
        );
    }
    let _ = writeln!(out, "{indent}}}");
}

fn write_prob(
    out: &mut String,
    p: &ProbPrim,
    joints: &[String],
    dims: usize,
    indent: &str,
    o: &PrintOptions,
) {
    let dist: Vec<String> = p
        .duration
        .counts
        .iter()
        .map(|(v, c)| format!("{v}: {c}"))
        .collect();
    let _ = writeln!(
        out,
        "{indent}motion(duration=sample({{{}}})) {{",
        dist.join(", ")
    );
    for (name, g) in joints.iter().zip(&p.joints) {
        let m = &g.mean;
        let mean = format!(
            "<{}, {}, {}>",
            point(&m[..dims], o),
            point(&m[dims..2 * dims], o),
            point(&m[2 * dims..], o)
        );
        if o.covariances {
            let cov: Vec<String> = g.cov.iter().map(|x| num(*x, o)).collect();
            let _ = writeln!(
                out,
                "{indent}  {name}: Gaussian(mean={mean}, cov=[{}])",
                cov.join(", ")
            );
        } else {
            let _ = writeln!(
                out,
                "{indent}  {name}: Gaussian(mean={mean})  # |cov| = {}",
                num(g.cov_norm(), o)
            );
        }
    }
    let _ = writeln!(out, "{indent}}}");
}

impl AbstractProgram {
    /// Prints a program with the given options.
    pub fn to_dsl_with(&self, o: &PrintOptions) -> String {
        let mut out = String::new();
        let _ = writeln!(
            out,
            "abstract_program(fps={}, units={}, dims={}, unit_scale={})",
            num(self.fps, &PrintOptions::default()),
            self.units,
            self.dims,
            num(self.unit_scale, &PrintOptions::default())
        );
        let _ = writeln!(out, "joints({})", self.joints.join(", "));
        for s in &self.stmts {
            match s {
                Stmt::Prim(d) => write_det(&mut out, d, &self.joints, self.dims, "", o),
                Stmt::Loop(l) => {
                    let _ = writeln!(out, "for i in range({}) {{", l.iterations);
                    for b in &l.body {
                        write_prob(&mut out, b, &self.joints, self.dims, "  ", o);
                    }
                    if o.observed && !l.observed.is_empty() {
                        let _ = writeln!(out, "  observed {{");
                        for it in &l.observed {
                            let _ = writeln!(out, "    iteration {{");
                            for d in it {
                                write_det(&mut out, d, &self.joints, self.dims, "      ", o);
                            }
                            let _ = writeln!(out, "    }}");
                        }
                        let _ = writeln!(out, "  }}");
                    }
                    let _ = writeln!(out, "}}");
                }
            }
        }
        out
    }

    /// Prints a program losslessly.
    pub fn to_dsl(&self) -> String {
        self.to_dsl_with(&PrintOptions::default())
    }
}

#[derive(Debug, Clone, PartialEq)]
enum Tok {
    Num(f64),
    Ident(String),
    Punct(char),
}

struct Lexer {
    toks: Vec<(Tok, usize, usize)>,
    pos: usize,
    end: (usize, usize),
}

/// The tokens of `src` by the workspace's one lexer
/// ([`LexRules::lex`] with [`LexRules::ABSTRACT`]), numbers read as `f64`.
fn lex(src: &str) -> Result<Lexer> {
    let located = |line, column, message: String| AbstractError::Parse {
        line,
        column,
        message,
    };
    let tokens = LexRules::ABSTRACT.lex(src).map_err(|e| {
        located(
            e.line,
            e.column,
            format!("expected {}, found {}", e.expected, e.found),
        )
    })?;
    let mut toks = Vec::with_capacity(tokens.len());
    let mut end = (1, 1);
    for t in tokens {
        let tok = match t.tok {
            shared::Tok::Number(text) => Tok::Num(
                text.parse()
                    .map_err(|_| located(t.line, t.column, format!("`{text}` is not a number")))?,
            ),
            shared::Tok::Ident(s) => Tok::Ident(s),
            shared::Tok::Punct(c) => Tok::Punct(c),
            shared::Tok::Eof => {
                end = (t.line, t.column);
                continue;
            }
            other => {
                return Err(located(
                    t.line,
                    t.column,
                    format!("unexpected {}", other.describe()),
                ))
            }
        };
        toks.push((tok, t.line, t.column));
    }
    Ok(Lexer { toks, pos: 0, end })
}

impl Lexer {
    fn here(&self) -> (usize, usize) {
        self.toks
            .get(self.pos)
            .map(|t| (t.1, t.2))
            .unwrap_or(self.end)
    }
    fn err<T>(&self, message: impl Into<String>) -> Result<T> {
        let (line, column) = self.here();
        Err(AbstractError::Parse {
            line,
            column,
            message: message.into(),
        })
    }
    fn peek(&self) -> Option<&Tok> {
        self.toks.get(self.pos).map(|t| &t.0)
    }
    fn describe(&self) -> String {
        match self.peek() {
            Some(Tok::Num(v)) => format!("number {v}"),
            Some(Tok::Ident(s)) => format!("`{s}`"),
            Some(Tok::Punct(c)) => format!("`{c}`"),
            None => "end of input".into(),
        }
    }
    fn punct(&mut self, c: char) -> Result<()> {
        if self.peek() == Some(&Tok::Punct(c)) {
            self.pos += 1;
            Ok(())
        } else {
            self.err(format!("expected `{c}`, found {}", self.describe()))
        }
    }
    fn is_punct(&self, c: char) -> bool {
        self.peek() == Some(&Tok::Punct(c))
    }
    fn ident(&mut self) -> Result<String> {
        match self.peek() {
            Some(Tok::Ident(s)) => {
                let s = s.clone();
                self.pos += 1;
                Ok(s)
            }
            _ => self.err(format!("expected a name, found {}", self.describe())),
        }
    }
    /// The joint `name` followed by `:` (joints come in the header's order).
    fn joint(&mut self, name: &str) -> Result<()> {
        let got = self.ident()?;
        if got != name {
            self.pos -= 1;
            return self.err(format!("expected joint `{name}`, found `{got}`"));
        }
        self.punct(':')
    }
    fn keyword(&mut self, k: &str) -> Result<()> {
        match self.peek() {
            Some(Tok::Ident(s)) if s == k => {
                self.pos += 1;
                Ok(())
            }
            _ => self.err(format!("expected `{k}`, found {}", self.describe())),
        }
    }
    fn is_keyword(&self, k: &str) -> bool {
        matches!(self.peek(), Some(Tok::Ident(s)) if s == k)
    }
    fn number(&mut self) -> Result<f64> {
        match self.peek() {
            Some(Tok::Num(v)) => {
                let v = *v;
                self.pos += 1;
                Ok(v)
            }
            Some(Tok::Ident(s)) if matches!(s.as_str(), "inf" | "NaN" | "nan") => {
                self.err(format!("non-finite number `{s}` is not allowed"))
            }
            _ => self.err(format!("expected a number, found {}", self.describe())),
        }
    }
    fn integer(&mut self, what: &str) -> Result<usize> {
        let at = self.pos;
        let v = self.number()?;
        if v < 0.0 || v.fract() != 0.0 || v > MAX_INTEGER as f64 {
            self.pos = at;
            return self.err(format!("{what} must be a non-negative integer, found {v}"));
        }
        Ok(v as usize)
    }
    fn kv_number(&mut self, key: &str) -> Result<f64> {
        self.keyword(key)?;
        self.punct('=')?;
        self.number()
    }
    fn point(&mut self, dims: usize) -> Result<Vec<f64>> {
        self.punct('(')?;
        let mut v = Vec::new();
        loop {
            v.push(self.number()?);
            if self.is_punct(',') {
                self.pos += 1;
            } else {
                break;
            }
        }
        if v.len() != dims {
            return self.err(format!(
                "point has {} coordinates, the program has dims={dims}",
                v.len()
            ));
        }
        self.punct(')')?;
        Ok(v)
    }
}

fn parse_det(lx: &mut Lexer, joints: &[String], dims: usize) -> Result<DetPrim> {
    lx.keyword("motion")?;
    lx.punct('(')?;
    lx.keyword("duration")?;
    lx.punct('=')?;
    let duration = lx.integer("duration")?;
    if duration == 0 {
        return lx.err("duration must be ≥ 1");
    }
    lx.punct(')')?;
    lx.punct('{')?;
    let mut points = Vec::with_capacity(joints.len());
    for name in joints {
        lx.joint(name)?;
        let mut v = Vec::new();
        for (i, key) in ["start", "mid", "end"].iter().enumerate() {
            if i > 0 {
                lx.punct(',')?;
            }
            lx.keyword(key)?;
            lx.punct('=')?;
            v.extend(lx.point(dims)?);
        }
        points.push(v);
    }
    lx.punct('}')?;
    Ok(DetPrim { duration, points })
}

fn parse_prob(lx: &mut Lexer, joints: &[String], dims: usize) -> Result<ProbPrim> {
    lx.keyword("motion")?;
    lx.punct('(')?;
    lx.keyword("duration")?;
    lx.punct('=')?;
    lx.keyword("sample")?;
    lx.punct('(')?;
    lx.punct('{')?;
    let mut dist = FreqDist::default();
    while !lx.is_punct('}') {
        let v = lx.integer("duration value")?;
        if v == 0 {
            return lx.err("durations must be ≥ 1");
        }
        lx.punct(':')?;
        let c = lx.integer("count")?;
        if !dist_total_fits(&dist.counts, c) {
            lx.pos -= 1;
            return lx.err("duration counts overflow");
        }
        *dist.counts.entry(v).or_insert(0) += c;
        if lx.is_punct(',') {
            lx.pos += 1;
        }
    }
    lx.punct('}')?;
    if dist.total() == 0 {
        return lx.err("empty duration distribution");
    }
    lx.punct(')')?;
    lx.punct(')')?;
    lx.punct('{')?;
    let n = dims.saturating_mul(3);
    let n2 = n.saturating_mul(n);
    let mut gs = Vec::with_capacity(joints.len());
    for name in joints {
        lx.joint(name)?;
        lx.keyword("Gaussian")?;
        lx.punct('(')?;
        lx.keyword("mean")?;
        lx.punct('=')?;
        lx.punct('<')?;
        let mut mean = lx.point(dims)?;
        lx.punct(',')?;
        mean.extend(lx.point(dims)?);
        lx.punct(',')?;
        mean.extend(lx.point(dims)?);
        lx.punct('>')?;
        lx.punct(',')?;
        lx.keyword("cov")?;
        lx.punct('=')?;
        lx.punct('[')?;
        let mut cov = Vec::new();
        while !lx.is_punct(']') {
            cov.push(lx.number()?);
            if lx.is_punct(',') {
                lx.pos += 1;
            }
        }
        if cov.len() != n2 {
            return lx.err(format!(
                "covariance has {} values, expected {n2}",
                cov.len()
            ));
        }
        lx.punct(']')?;
        lx.punct(')')?;
        gs.push(Gaussian { mean, cov });
    }
    lx.punct('}')?;
    Ok(ProbPrim {
        duration: dist,
        joints: gs,
    })
}

/// Largest integer of the text form (durations, counts, iterations, dims).
pub const MAX_INTEGER: usize = 1_000_000_000_000;

/// Whether adding `c` to the counts keeps their total within `usize`.
fn dist_total_fits(counts: &std::collections::BTreeMap<usize, usize>, c: usize) -> bool {
    counts
        .values()
        .try_fold(0usize, |a, &x| a.checked_add(x))
        .and_then(|t| t.checked_add(c))
        .is_some()
}

/// Whether `s` reads back as one name in the text form (a joint name):
/// letters, digits, `_`, `-`, `.` and `|`, not starting like a number.
pub fn is_name(s: &str) -> bool {
    match LexRules::ABSTRACT.lex(s).as_deref() {
        Ok(
            [shared::Token {
                tok: shared::Tok::Ident(name),
                ..
            }, shared::Token {
                tok: shared::Tok::Eof,
                ..
            }],
        ) => name == s,
        _ => false,
    }
}

impl AbstractProgram {
    /// Parses the text form back into a program (and validates it).
    pub fn from_dsl(src: &str) -> Result<AbstractProgram> {
        let mut lx = lex(src)?;
        lx.keyword("abstract_program")?;
        lx.punct('(')?;
        let fps = lx.kv_number("fps")?;
        lx.punct(',')?;
        lx.keyword("units")?;
        lx.punct('=')?;
        let units = match lx.peek() {
            Some(Tok::Num(v)) if *v == 1.0 => {
                lx.pos += 1;
                "1".to_string()
            }
            _ => lx.ident()?,
        };
        if !matches!(units.as_str(), "px" | "m" | "1") {
            lx.pos -= 1;
            return lx.err(format!("units must be px, m or 1, found `{units}`"));
        }
        lx.punct(',')?;
        lx.keyword("dims")?;
        lx.punct('=')?;
        let dims = lx.integer("dims")?;
        if dims == 0 || (dims > 3 && units != "1") {
            lx.pos -= 1;
            return lx.err(format!(
                "dims must be 1, 2 or 3 (any ≥ 1 with units=1), found {dims}"
            ));
        }
        let unit_scale = if lx.is_punct(',') {
            lx.pos += 1;
            lx.kv_number("unit_scale")?
        } else {
            1.0
        };
        lx.punct(')')?;
        lx.keyword("joints")?;
        lx.punct('(')?;
        let mut joints = Vec::new();
        while !lx.is_punct(')') {
            joints.push(lx.ident()?);
            if lx.is_punct(',') {
                lx.pos += 1;
            }
        }
        lx.punct(')')?;
        if joints.is_empty() {
            return lx.err("a program needs at least one joint");
        }
        let mut stmts = Vec::new();
        while lx.peek().is_some() {
            if lx.is_keyword("motion") {
                stmts.push(Stmt::Prim(parse_det(&mut lx, &joints, dims)?));
            } else if lx.is_keyword("for") {
                lx.keyword("for")?;
                lx.ident()?;
                lx.keyword("in")?;
                lx.keyword("range")?;
                lx.punct('(')?;
                let iterations = lx.integer("iterations")?;
                lx.punct(')')?;
                lx.punct('{')?;
                let mut body = Vec::new();
                while lx.is_keyword("motion") {
                    body.push(parse_prob(&mut lx, &joints, dims)?);
                }
                if body.is_empty() {
                    return lx.err("a loop body needs at least one motion");
                }
                let mut observed = Vec::new();
                if lx.is_keyword("observed") {
                    lx.keyword("observed")?;
                    lx.punct('{')?;
                    while lx.is_keyword("iteration") {
                        lx.keyword("iteration")?;
                        lx.punct('{')?;
                        let mut it = Vec::new();
                        while lx.is_keyword("motion") {
                            it.push(parse_det(&mut lx, &joints, dims)?);
                        }
                        lx.punct('}')?;
                        observed.push(it);
                    }
                    lx.punct('}')?;
                }
                lx.punct('}')?;
                stmts.push(Stmt::Loop(Loop {
                    iterations,
                    body,
                    observed,
                }));
            } else {
                return lx.err(format!(
                    "expected `motion` or `for`, found {}",
                    lx.describe()
                ));
            }
        }
        let prog = AbstractProgram {
            fps,
            units,
            dims,
            unit_scale,
            joints,
            stmts,
        };
        prog.validate()?;
        Ok(prog)
    }
}
