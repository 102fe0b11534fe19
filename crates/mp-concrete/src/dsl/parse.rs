//! A hand-written recursive-descent parser for the concrete DSL.

use mp_geom::{Primitive, Units};

use super::lex::{LexRules, Tok, Token};
use super::print::axis_name;
use crate::error::{ConcreteError, ParseError, Result};
use crate::program::{Program, Segment};
use crate::smooth::Continuity;

/// The fields of the program header.
struct Header {
    fps: f64,
    units: Units,
    dims: usize,
    skeleton: String,
    continuity: Continuity,
}

/// A term `coef * t ^ power` of a polynomial.
#[derive(Debug, Clone)]
struct Term {
    coef: f64,
    power: u32,
    at: (usize, usize),
}

#[derive(Debug, Clone)]
enum Value {
    Tuple(Vec<f64>),
    Poly(Vec<Term>),
    Int(usize),
}

#[derive(Debug, Clone)]
struct Arg {
    key: String,
    key_at: (usize, usize),
    value: Value,
    value_at: (usize, usize),
}

struct Parser {
    toks: Vec<Token>,
    pos: usize,
}

fn perr(at: (usize, usize), expected: impl Into<String>, found: impl Into<String>) -> ParseError {
    ParseError {
        line: at.0,
        column: at.1,
        expected: expected.into(),
        found: found.into(),
    }
}

type PResult<T> = std::result::Result<T, ParseError>;

impl Parser {
    fn peek(&self) -> &Token {
        // `LexRules::lex` always ends with `Eof`, and `bump` never moves past it.
        &self.toks[self.pos.min(self.toks.len() - 1)]
    }
    fn at(&self) -> (usize, usize) {
        let t = self.peek();
        (t.line, t.column)
    }
    fn bump(&mut self) -> Token {
        let t = self.peek().clone();
        if self.pos < self.toks.len() - 1 {
            self.pos += 1;
        }
        t
    }
    fn unexpected<T>(&self, expected: impl Into<String>) -> PResult<T> {
        Err(perr(self.at(), expected, self.peek().tok.describe()))
    }
    fn expect(&mut self, tok: Tok, expected: &str) -> PResult<Token> {
        if self.peek().tok == tok {
            Ok(self.bump())
        } else {
            self.unexpected(expected)
        }
    }
    fn eat(&mut self, tok: &Tok) -> bool {
        if &self.peek().tok == tok {
            self.bump();
            true
        } else {
            false
        }
    }
    fn ident(&mut self, expected: &str) -> PResult<(String, (usize, usize))> {
        let at = self.at();
        match &self.peek().tok {
            Tok::Ident(s) => {
                let s = s.clone();
                self.bump();
                Ok((s, at))
            }
            _ => self.unexpected(expected),
        }
    }
    fn keyword(&mut self, kw: &str) -> PResult<()> {
        match &self.peek().tok {
            Tok::Ident(s) if s == kw => {
                self.bump();
                Ok(())
            }
            _ => self.unexpected(format!("`{kw}`")),
        }
    }
    fn string(&mut self, expected: &str) -> PResult<(String, (usize, usize))> {
        let at = self.at();
        match &self.peek().tok {
            Tok::Str(s) => {
                let s = s.clone();
                self.bump();
                Ok((s, at))
            }
            _ => self.unexpected(expected),
        }
    }
    /// `[+|-] NUMBER` as a finite f64.
    fn signed_number(&mut self) -> PResult<(f64, (usize, usize))> {
        let at = self.at();
        let neg = if self.eat(&Tok::Punct('-')) {
            true
        } else {
            self.eat(&Tok::Punct('+'));
            false
        };
        let nat = self.at();
        let raw = match &self.peek().tok {
            Tok::Number(s) => s.clone(),
            _ => return self.unexpected("a number"),
        };
        self.bump();
        let v: f64 = raw
            .parse()
            .map_err(|_| perr(nat, "a number", format!("`{raw}`")))?;
        if !v.is_finite() {
            return Err(perr(
                nat,
                "a finite number",
                format!("`{raw}` (out of range)"),
            ));
        }
        Ok((if neg { -v } else { v }, at))
    }
    fn integer(&mut self, expected: &str) -> PResult<(usize, (usize, usize))> {
        let at = self.at();
        let raw = match &self.peek().tok {
            Tok::Number(s) => s.clone(),
            _ => return self.unexpected(expected),
        };
        if !raw.bytes().all(|b| b.is_ascii_digit()) {
            return Err(perr(at, expected, format!("`{raw}`")));
        }
        self.bump();
        let v = raw
            .parse::<usize>()
            .map_err(|_| perr(at, expected, format!("`{raw}` (too large)")))?;
        Ok((v, at))
    }
    /// `( n, n, … )`
    fn tuple(&mut self) -> PResult<Vec<f64>> {
        self.expect(Tok::Punct('('), "`(`")?;
        let mut v = vec![self.signed_number()?.0];
        while self.eat(&Tok::Punct(',')) {
            v.push(self.signed_number()?.0);
        }
        self.expect(Tok::Punct(')'), "`,` or `)`")?;
        Ok(v)
    }
    /// `term ((+|-) term)*` with `term = [+|-] NUMBER [* t [^ INT]]`.
    fn poly(&mut self) -> PResult<Vec<Term>> {
        let mut terms = vec![self.term(false)?];
        loop {
            let neg = match self.peek().tok {
                Tok::Punct('+') => false,
                Tok::Punct('-') => true,
                _ => break,
            };
            self.bump();
            terms.push(self.term(neg)?);
        }
        Ok(terms)
    }
    fn term(&mut self, negate: bool) -> PResult<Term> {
        let (c, at) = self.signed_number()?;
        let coef = if negate { -c } else { c };
        let mut power = 0;
        if self.eat(&Tok::Punct('*')) {
            match &self.peek().tok {
                Tok::Ident(s) if s == "t" => {
                    self.bump();
                }
                _ => return self.unexpected("`t`"),
            }
            power = 1;
            if self.eat(&Tok::Punct('^')) {
                let (p, pat) = self.integer("an integer power")?;
                power = u32::try_from(p)
                    .map_err(|_| perr(pat, "a power 1, 2 or 3", format!("`{p}`")))?;
            }
        }
        Ok(Term { coef, power, at })
    }

    fn header(&mut self) -> PResult<Header> {
        self.keyword("program")?;
        self.expect(Tok::Punct('('), "`(`")?;
        let (mut fps, mut units, mut dims, mut skel, mut cont) = (None, None, None, None, None);
        loop {
            let (key, kat) = self.ident("`fps`, `units`, `dims`, `skeleton` or `continuity`")?;
            self.expect(Tok::Punct('='), "`=`")?;
            let dup = match key.as_str() {
                "fps" => {
                    let (v, at) = self.signed_number()?;
                    if v <= 0.0 {
                        return Err(perr(at, "a frame rate > 0", format!("`{v}`")));
                    }
                    fps.replace(v).is_some()
                }
                "units" => {
                    let (u, at) = self.ident("`px`, `m` or `unitless`")?;
                    let u = Units::parse(&u)
                        .map_err(|_| perr(at, "`px`, `m` or `unitless`", format!("`{u}`")))?;
                    units.replace(u).is_some()
                }
                "dims" => {
                    let (d, at) = self.integer("a number of dimensions ≥ 1")?;
                    if d == 0 {
                        return Err(perr(at, "a number of dimensions ≥ 1", "`0`"));
                    }
                    dims.replace(d).is_some()
                }
                "skeleton" => {
                    let (s, _) = self.string("a quoted skeleton name")?;
                    skel.replace(s).is_some()
                }
                "continuity" => {
                    let (c, at) = self.ident("`none` or `c0`")?;
                    let c = Continuity::from_name(&c)
                        .ok_or_else(|| perr(at, "`none` or `c0`", format!("`{c}`")))?;
                    cont.replace(c).is_some()
                }
                _ => {
                    return Err(perr(
                        kat,
                        "`fps`, `units`, `dims`, `skeleton` or `continuity`",
                        format!("`{key}`"),
                    ))
                }
            };
            if dup {
                return Err(perr(
                    kat,
                    format!("`{key}` only once"),
                    format!("`{key}` again"),
                ));
            }
            if !self.eat(&Tok::Punct(',')) {
                break;
            }
        }
        let close = self.at();
        self.expect(Tok::Punct(')'), "`,` or `)`")?;
        self.eat(&Tok::Punct(';'));
        let missing = |what: &str| perr(close, format!("`{what}=` in the program header"), "`)`");
        Ok(Header {
            fps: fps.ok_or_else(|| missing("fps"))?,
            units: units.ok_or_else(|| missing("units"))?,
            dims: dims.ok_or_else(|| missing("dims"))?,
            skeleton: skel.unwrap_or_else(|| "generic".into()),
            continuity: cont.unwrap_or_default(),
        })
    }

    fn args(&mut self) -> PResult<(Vec<Arg>, (usize, usize))> {
        self.expect(Tok::Punct('('), "`(`")?;
        let mut args: Vec<Arg> = Vec::new();
        loop {
            let (key, key_at) = self.ident("an argument name")?;
            if args.iter().any(|a| a.key == key) {
                return Err(perr(
                    key_at,
                    format!("`{key}` only once"),
                    format!("`{key}` again"),
                ));
            }
            self.expect(Tok::Punct('='), "`=`")?;
            let value_at = self.at();
            let value = if key == "duration" {
                let (d, at) = self.integer("a duration in frames (an integer ≥ 1)")?;
                if d == 0 {
                    return Err(perr(at, "a duration in frames (an integer ≥ 1)", "`0`"));
                }
                Value::Int(d)
            } else if self.peek().tok == Tok::Punct('(') {
                Value::Tuple(self.tuple()?)
            } else {
                Value::Poly(self.poly()?)
            };
            args.push(Arg {
                key,
                key_at,
                value,
                value_at,
            });
            if !self.eat(&Tok::Punct(',')) {
                break;
            }
        }
        let close = self.at();
        self.expect(Tok::Punct(')'), "`,` or `)`")?;
        Ok((args, close))
    }

    /// One statement → (primitive, duration, position of the duration value).
    fn statement(&mut self, dims: usize) -> PResult<(Primitive, usize, (usize, usize))> {
        let (name, name_at) = self.ident("a primitive")?;
        const PRIMS: &str = "`stationary`, `linear_motion`, `circular_motion` or `spline_motion`";
        if !matches!(
            name.as_str(),
            "stationary" | "linear_motion" | "circular_motion" | "spline_motion"
        ) {
            return Err(perr(name_at, PRIMS, format!("`{name}`")));
        }
        let (args, close) = self.args()?;
        self.eat(&Tok::Punct(';'));
        // The axes are named one by one, never listed in full: `dims` comes
        // from the header and may be far larger than the statement.
        const CIRCLE_KEYS: [&str; 5] = ["center", "radius", "angle", "u", "v"];
        let circle = name == "circular_motion";
        for a in &args {
            let ok = a.key == "duration"
                || if circle {
                    CIRCLE_KEYS.contains(&a.key.as_str())
                } else {
                    is_axis(&a.key, dims)
                };
            if !ok {
                let mut list: Vec<String> = if circle {
                    CIRCLE_KEYS.iter().map(|k| format!("`{k}`")).collect()
                } else if dims <= 8 {
                    (0..dims)
                        .map(|k| format!("`{}`", axis_name(k, dims)))
                        .collect()
                } else {
                    vec![format!("`x0` … `x{}`", dims - 1)]
                };
                list.push("`duration`".into());
                return Err(perr(
                    a.key_at,
                    format!("one of {} for `{name}` in {dims}D", list.join(", ")),
                    format!("`{}`", a.key),
                ));
            }
        }
        // Lazily, so that a missing axis stops the loop at once.
        let axes = (0..dims).map(|k| axis_name(k, dims));
        let get = |key: &str| args.iter().find(|a| a.key == key);
        let need =
            |key: &str| get(key).ok_or_else(|| perr(close, format!("`{key}=` in `{name}`"), "`)`"));
        let dur = need("duration")?;
        let (duration, dur_at) = match dur.value {
            Value::Int(d) => (d, dur.value_at),
            _ => return Err(perr(dur.value_at, "an integer duration", "something else")),
        };
        // Polynomial of degree ≤ max_pow → coefficients highest power first (len max_pow + 1).
        let poly_of = |a: &Arg, max_pow: u32, what: &str| -> PResult<Vec<f64>> {
            let terms = match &a.value {
                Value::Poly(t) => t,
                _ => return Err(perr(a.value_at, what.to_string(), "a tuple")),
            };
            let mut c = vec![0.0; max_pow as usize + 1];
            let mut seen = vec![false; max_pow as usize + 1];
            for t in terms {
                if t.power > max_pow {
                    return Err(perr(
                        t.at,
                        what.to_string(),
                        format!("a term in t^{}", t.power),
                    ));
                }
                let idx = (max_pow - t.power) as usize;
                if seen[idx] {
                    return Err(perr(
                        t.at,
                        format!("one term in t^{} only", t.power),
                        "a second one",
                    ));
                }
                seen[idx] = true;
                c[idx] = t.coef;
            }
            Ok(c)
        };
        let tuple_of = |a: &Arg, what: &str| -> PResult<Vec<f64>> {
            match &a.value {
                Value::Tuple(v) if v.len() == dims => Ok(v.clone()),
                Value::Tuple(v) => Err(perr(
                    a.value_at,
                    what.to_string(),
                    format!("a tuple of {}", v.len()),
                )),
                _ => Err(perr(a.value_at, what.to_string(), "a polynomial")),
            }
        };
        let prim = match name.as_str() {
            "stationary" => {
                let mut point = Vec::new();
                for ax in axes {
                    point.push(poly_of(need(&ax)?, 0, "a number")?[0]);
                }
                Primitive::Stationary { point }
            }
            "linear_motion" => {
                let (mut start, mut velocity) = (Vec::new(), Vec::new());
                for ax in axes {
                    let c = poly_of(need(&ax)?, 1, "`velocity*t + start`")?;
                    velocity.push(c[0]);
                    start.push(c[1]);
                }
                Primitive::Line { start, velocity }
            }
            "spline_motion" => {
                let mut coeffs = Vec::new();
                for ax in axes {
                    let c = poly_of(need(&ax)?, 3, "`a*t^3 + b*t^2 + c*t + d`")?;
                    coeffs.push([c[0], c[1], c[2], c[3]]);
                }
                Primitive::Spline { coeffs }
            }
            _ => {
                if dims < 2 {
                    return Err(perr(
                        name_at,
                        "a primitive for 1D (no circle in 1D)",
                        "`circular_motion`",
                    ));
                }
                let what = format!("a point of {dims} numbers");
                let center = tuple_of(need("center")?, &what)?;
                let r = need("radius")?;
                let radius = poly_of(r, 0, "a radius")?[0];
                if radius < 0.0 {
                    return Err(perr(r.value_at, "a radius ≥ 0", format!("`{radius}`")));
                }
                let a = poly_of(
                    need("angle")?,
                    2,
                    "`velocity*t + start` (optionally `acc*t^2 + …`)",
                )?;
                let axes = match (get("u"), get("v")) {
                    (None, None) => Vec::new(),
                    (Some(u), Some(v)) => vec![tuple_of(u, &what)?, tuple_of(v, &what)?],
                    (Some(_), None) => return Err(perr(close, "`v=` with `u=`", "`)`")),
                    (None, Some(_)) => return Err(perr(close, "`u=` with `v=`", "`)`")),
                };
                Primitive::Circle {
                    center,
                    radius,
                    angle_start: a[2],
                    angle_vel: a[1],
                    angle_acc: a[0],
                    axes,
                }
            }
        };
        Ok((prim, duration, dur_at))
    }

    fn program(&mut self) -> PResult<Program> {
        let Header {
            fps,
            units,
            dims,
            skeleton,
            continuity,
        } = self.header()?;
        let mut joints: Vec<String> = Vec::new();
        let mut segments: Vec<Segment> = Vec::new();
        loop {
            if self.peek().tok == Tok::Eof {
                if joints.is_empty() {
                    return self.unexpected("`joint`");
                }
                break;
            }
            self.keyword("joint")?;
            let (jname, jat) = self.string("a quoted joint name")?;
            if jname.is_empty() {
                return Err(perr(jat, "a non-empty joint name", "`\"\"`"));
            }
            if joints.contains(&jname) {
                return Err(perr(
                    jat,
                    "a joint name not used before",
                    format!("{jname:?} again"),
                ));
            }
            self.expect(Tok::Punct('{'), "`{`")?;
            let first = joints.is_empty();
            let mut i = 0usize;
            while self.peek().tok != Tok::Punct('}') {
                if self.peek().tok == Tok::Eof {
                    return self.unexpected("a statement or `}`");
                }
                let st_at = self.at();
                let (prim, dur, dur_at) = self.statement(dims)?;
                if first {
                    segments.push(Segment {
                        duration_frames: dur,
                        primitives: vec![prim],
                    });
                } else {
                    let Some(seg) = segments.get_mut(i) else {
                        return Err(perr(
                            st_at,
                            format!("`}}` ({} statements, as in joint {:?})", i, joints[0]),
                            "another statement",
                        ));
                    };
                    if seg.duration_frames != dur {
                        return Err(perr(
                            dur_at,
                            format!(
                                "duration={} (segment {} of joint {:?}; all joints share the segmentation)",
                                seg.duration_frames, i, joints[0]
                            ),
                            format!("duration={dur}"),
                        ));
                    }
                    seg.primitives.push(prim);
                }
                i += 1;
            }
            if first && i == 0 {
                return self.unexpected("a statement");
            }
            if i < segments.len() {
                return self.unexpected(format!(
                    "a statement ({} statements, as in joint {:?})",
                    segments.len(),
                    joints[0]
                ));
            }
            self.bump();
            joints.push(jname);
        }
        Ok(Program {
            fps,
            units,
            dims,
            skeleton,
            joints,
            continuity,
            segments,
        })
    }
}

/// Whether `key` names an axis of a `dims`-dimensional program
/// ([`axis_name`]: `x`, `y`, `z` up to 3D, else `x0`, `x1`, …).
fn is_axis(key: &str, dims: usize) -> bool {
    if dims <= 3 {
        ["x", "y", "z"][..dims].contains(&key)
    } else {
        key.strip_prefix('x')
            .and_then(|k| k.parse::<usize>().ok())
            .is_some_and(|k| k < dims && axis_name(k, dims) == key)
    }
}

/// Parses the text of a whole program (see `docs/DSL.md`) and validates it.
pub(crate) fn parse(text: &str) -> Result<Program> {
    let toks = LexRules::CONCRETE.lex(text)?;
    let mut p = Parser { toks, pos: 0 };
    let prog = p.program().map_err(ConcreteError::from)?;
    prog.validate()?;
    Ok(prog)
}

/// Parses one statement (e.g. `stationary(x=1, y=2, duration=3)`) for a program of `dims` dimensions.
#[cfg(test)]
pub fn parse_statement(text: &str, dims: usize) -> Result<(Primitive, usize)> {
    let toks = LexRules::CONCRETE.lex(text)?;
    let mut p = Parser { toks, pos: 0 };
    let (prim, dur, _) = p.statement(dims)?;
    if p.peek().tok != Tok::Eof {
        return Err(perr(p.at(), "end of input", p.peek().tok.describe()).into());
    }
    Ok((prim, dur))
}
