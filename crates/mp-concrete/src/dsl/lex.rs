//! Tokens of the DSL, with 1-based line and column (in characters).

use crate::error::ParseError;

#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Tok {
    Ident(String),
    /// A number literal as written (digits, optional fraction, optional exponent).
    Number(String),
    Str(String),
    LParen,
    RParen,
    LBrace,
    RBrace,
    Comma,
    Eq,
    Star,
    Caret,
    Plus,
    Minus,
    Semi,
    Eof,
}

impl Tok {
    pub(crate) fn describe(&self) -> String {
        match self {
            Tok::Ident(s) => format!("`{s}`"),
            Tok::Number(s) => format!("number `{s}`"),
            Tok::Str(s) => format!("string {s:?}"),
            Tok::LParen => "`(`".into(),
            Tok::RParen => "`)`".into(),
            Tok::LBrace => "`{`".into(),
            Tok::RBrace => "`}`".into(),
            Tok::Comma => "`,`".into(),
            Tok::Eq => "`=`".into(),
            Tok::Star => "`*`".into(),
            Tok::Caret => "`^`".into(),
            Tok::Plus => "`+`".into(),
            Tok::Minus => "`-`".into(),
            Tok::Semi => "`;`".into(),
            Tok::Eof => "end of input".into(),
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Token {
    pub tok: Tok,
    pub line: usize,
    pub column: usize,
}

/// Splits text into tokens. `#` starts a comment that runs to the end of the line.
pub(crate) fn lex(text: &str) -> Result<Vec<Token>, ParseError> {
    let chars: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let (mut i, mut line, mut col) = (0usize, 1usize, 1usize);
    let err = |line, column, expected: &str, found: String| ParseError {
        line,
        column,
        expected: expected.into(),
        found,
    };
    while i < chars.len() {
        let c = chars[i];
        let (tl, tc) = (line, col);
        if c == '\n' {
            i += 1;
            line += 1;
            col = 1;
            continue;
        }
        if c.is_whitespace() {
            i += 1;
            col += 1;
            continue;
        }
        if c == '#' {
            while i < chars.len() && chars[i] != '\n' {
                i += 1;
                col += 1;
            }
            continue;
        }
        let single = match c {
            '(' => Some(Tok::LParen),
            ')' => Some(Tok::RParen),
            '{' => Some(Tok::LBrace),
            '}' => Some(Tok::RBrace),
            ',' => Some(Tok::Comma),
            '=' => Some(Tok::Eq),
            '*' => Some(Tok::Star),
            '^' => Some(Tok::Caret),
            '+' => Some(Tok::Plus),
            '-' => Some(Tok::Minus),
            ';' => Some(Tok::Semi),
            _ => None,
        };
        if let Some(tok) = single {
            out.push(Token {
                tok,
                line: tl,
                column: tc,
            });
            i += 1;
            col += 1;
            continue;
        }
        if c.is_ascii_alphabetic() || c == '_' {
            let start = i;
            while i < chars.len() && (chars[i].is_ascii_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            col += i - start;
            out.push(Token {
                tok: Tok::Ident(chars[start..i].iter().collect()),
                line: tl,
                column: tc,
            });
            continue;
        }
        if c.is_ascii_digit() {
            let start = i;
            let digits = |i: &mut usize| {
                let s = *i;
                while *i < chars.len() && chars[*i].is_ascii_digit() {
                    *i += 1;
                }
                *i > s
            };
            digits(&mut i);
            if i < chars.len() && chars[i] == '.' {
                i += 1;
                if !digits(&mut i) {
                    let found = chars
                        .get(i)
                        .map_or("end of input".to_string(), |c| format!("`{c}`"));
                    return Err(err(line, col + (i - start), "a digit after `.`", found));
                }
            }
            if i < chars.len() && (chars[i] == 'e' || chars[i] == 'E') {
                i += 1;
                if i < chars.len() && (chars[i] == '+' || chars[i] == '-') {
                    i += 1;
                }
                if !digits(&mut i) {
                    let found = chars
                        .get(i)
                        .map_or("end of input".to_string(), |c| format!("`{c}`"));
                    return Err(err(
                        line,
                        col + (i - start),
                        "a digit in the exponent",
                        found,
                    ));
                }
            }
            col += i - start;
            out.push(Token {
                tok: Tok::Number(chars[start..i].iter().collect()),
                line: tl,
                column: tc,
            });
            continue;
        }
        if c == '"' {
            i += 1;
            col += 1;
            let mut s = String::new();
            loop {
                match chars.get(i) {
                    None | Some('\n') => {
                        return Err(err(
                            line,
                            col,
                            "`\"` closing the string",
                            "end of line".into(),
                        ))
                    }
                    Some('"') => {
                        i += 1;
                        col += 1;
                        break;
                    }
                    Some('\\') => {
                        let e = match chars.get(i + 1) {
                            Some('"') => '"',
                            Some('\\') => '\\',
                            Some('n') => '\n',
                            Some('t') => '\t',
                            other => {
                                let found = other
                                    .map_or("end of input".to_string(), |c| format!("`\\{c}`"));
                                return Err(err(
                                    line,
                                    col,
                                    "an escape `\\\"`, `\\\\`, `\\n` or `\\t`",
                                    found,
                                ));
                            }
                        };
                        s.push(e);
                        i += 2;
                        col += 2;
                    }
                    Some(&ch) => {
                        s.push(ch);
                        i += 1;
                        col += 1;
                    }
                }
            }
            out.push(Token {
                tok: Tok::Str(s),
                line: tl,
                column: tc,
            });
            continue;
        }
        return Err(err(
            tl,
            tc,
            "a name, number, string or punctuation",
            format!("`{c}`"),
        ));
    }
    out.push(Token {
        tok: Tok::Eof,
        line,
        column: col,
    });
    Ok(out)
}
