//! The tokens of the workspace's program notations, with 1-based line and
//! column (in characters): the concrete DSL ([`LexRules::CONCRETE`]) and
//! the abstract programs of `mp-abstract` ([`LexRules::ABSTRACT`]) share
//! this lexer and differ only in their [`LexRules`].
//!
//! `#` starts a comment that runs to the end of the line. Numbers are
//! decimal: digits, an optional fraction (a digit must follow the `.`) and
//! an optional exponent; with [`LexRules::signed_numbers`] a sign directly
//! before the number belongs to it, and a number may start with `.`.

use crate::error::ParseError;

/// What a notation's tokens look like.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LexRules {
    /// Characters that are one token each.
    pub punctuation: &'static str,
    /// Characters besides ASCII letters, digits and `_` allowed anywhere in
    /// a name.
    pub name_chars: &'static str,
    /// Letters and digits of any script in names (otherwise ASCII only).
    pub unicode_names: bool,
    /// `-1.5`, `+2` and `.5` are single numbers (otherwise `-` and `+` are
    /// punctuation or name characters, and a number starts with a digit).
    pub signed_numbers: bool,
    /// Double-quoted strings with the escapes `\"`, `\\`, `\n` and `\t`.
    pub strings: bool,
}

impl LexRules {
    /// The concrete DSL (docs/DSL.md): ASCII names, strings, and the
    /// arithmetic of `a*t^2 + b*t + c` as punctuation.
    pub const CONCRETE: LexRules = LexRules {
        punctuation: "(){},=*^+-;",
        name_chars: "",
        unicode_names: false,
        signed_numbers: false,
        strings: true,
    };

    /// Abstract programs: joint names with `-`, `.` and `|` in any script,
    /// signed numbers, no strings.
    pub const ABSTRACT: LexRules = LexRules {
        punctuation: "(){}<>[],:=",
        name_chars: "-.|",
        unicode_names: true,
        signed_numbers: true,
        strings: false,
    };

    fn name_start(&self, c: char) -> bool {
        c.is_ascii_alphabetic()
            || c == '_'
            || self.name_chars.contains(c)
            || (self.unicode_names && c.is_alphabetic())
    }

    fn name_char(&self, c: char) -> bool {
        c.is_ascii_alphanumeric()
            || c == '_'
            || self.name_chars.contains(c)
            || (self.unicode_names && c.is_alphanumeric())
    }

    /// Whether a number starts at `chars[i..]`.
    fn number_start(&self, chars: &[char], i: usize) -> bool {
        let digit_at = |k: usize| chars.get(k).is_some_and(char::is_ascii_digit);
        match chars[i] {
            c if c.is_ascii_digit() => true,
            '.' => self.signed_numbers && digit_at(i + 1),
            '-' | '+' => {
                self.signed_numbers
                    && (digit_at(i + 1) || (chars.get(i + 1) == Some(&'.') && digit_at(i + 2)))
            }
            _ => false,
        }
    }

    /// What a token may start with, for errors.
    fn expected(&self) -> &'static str {
        if self.strings {
            "a name, number, string or punctuation"
        } else {
            "a name, number or punctuation"
        }
    }
}

/// One token.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Tok {
    /// A name or keyword.
    Ident(String),
    /// A number literal as written (sign, digits, fraction, exponent).
    Number(String),
    /// A string literal, escapes resolved.
    Str(String),
    /// A punctuation character of the rules.
    Punct(char),
    /// The end of the text (always the last token).
    Eof,
}

impl Tok {
    /// The token as an error message names it.
    pub fn describe(&self) -> String {
        match self {
            Tok::Ident(s) => format!("`{s}`"),
            Tok::Number(s) => format!("number `{s}`"),
            Tok::Str(s) => format!("string {s:?}"),
            Tok::Punct(c) => format!("`{c}`"),
            Tok::Eof => "end of input".into(),
        }
    }
}

/// A token and where it starts.
#[derive(Debug, Clone, PartialEq)]
pub struct Token {
    /// The token.
    pub tok: Tok,
    /// 1-based line.
    pub line: usize,
    /// 1-based column, in characters.
    pub column: usize,
}

impl LexRules {
    /// Splits `text` into tokens by these rules, ending with [`Tok::Eof`].
    pub fn lex(&self, text: &str) -> Result<Vec<Token>, ParseError> {
        let chars: Vec<char> = text.chars().collect();
        let mut out = Vec::new();
        let (mut i, mut line, mut col) = (0usize, 1usize, 1usize);
        let err = |line, column, expected: &str, found: String| ParseError {
            line,
            column,
            expected: expected.into(),
            found,
        };
        let found_at = |i: usize| {
            chars
                .get(i)
                .map_or("end of input".to_string(), |c| format!("`{c}`"))
        };
        while i < chars.len() {
            let c = chars[i];
            let (tl, tc) = (line, col);
            let mut push = |tok| {
                out.push(Token {
                    tok,
                    line: tl,
                    column: tc,
                })
            };
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
            if self.number_start(&chars, i) {
                let start = i;
                let digits = |i: &mut usize| {
                    let s = *i;
                    while *i < chars.len() && chars[*i].is_ascii_digit() {
                        *i += 1;
                    }
                    *i > s
                };
                if chars[i] == '-' || chars[i] == '+' {
                    i += 1;
                }
                digits(&mut i);
                if i < chars.len() && chars[i] == '.' {
                    i += 1;
                    if !digits(&mut i) {
                        return Err(err(
                            line,
                            col + (i - start),
                            "a digit after `.`",
                            found_at(i),
                        ));
                    }
                }
                if i < chars.len() && (chars[i] == 'e' || chars[i] == 'E') {
                    i += 1;
                    if i < chars.len() && (chars[i] == '+' || chars[i] == '-') {
                        i += 1;
                    }
                    if !digits(&mut i) {
                        return Err(err(
                            line,
                            col + (i - start),
                            "a digit in the exponent",
                            found_at(i),
                        ));
                    }
                }
                col += i - start;
                push(Tok::Number(chars[start..i].iter().collect()));
                continue;
            }
            if self.punctuation.contains(c) {
                push(Tok::Punct(c));
                i += 1;
                col += 1;
                continue;
            }
            if self.name_start(c) {
                let start = i;
                while i < chars.len() && self.name_char(chars[i]) {
                    i += 1;
                }
                col += i - start;
                push(Tok::Ident(chars[start..i].iter().collect()));
                continue;
            }
            if c == '"' && self.strings {
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
                push(Tok::Str(s));
                continue;
            }
            return Err(err(tl, tc, self.expected(), format!("`{c}`")));
        }
        out.push(Token {
            tok: Tok::Eof,
            line,
            column: col,
        });
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn toks(text: &str, rules: &LexRules) -> Vec<Tok> {
        rules
            .lex(text)
            .unwrap()
            .into_iter()
            .map(|t| t.tok)
            .collect()
    }

    #[test]
    fn concrete_signs_are_punctuation_and_abstract_signs_belong_to_numbers() {
        use Tok::*;
        assert_eq!(
            toks("x=-1.5e3*t", &LexRules::CONCRETE),
            vec![
                Ident("x".into()),
                Punct('='),
                Punct('-'),
                Number("1.5e3".into()),
                Punct('*'),
                Ident("t".into()),
                Eof
            ]
        );
        assert_eq!(
            toks("(-1.5e3, .5) r-knee|2 # note", &LexRules::ABSTRACT),
            vec![
                Punct('('),
                Number("-1.5e3".into()),
                Punct(','),
                Number(".5".into()),
                Punct(')'),
                Ident("r-knee|2".into()),
                Eof
            ]
        );
    }

    #[test]
    fn positions_and_errors_are_located() {
        let t = LexRules::CONCRETE.lex("a\n  \"s\\\"\" 7").unwrap();
        assert_eq!((t[1].line, t[1].column), (2, 3));
        assert_eq!(t[1].tok, Tok::Str("s\"".into()));
        assert_eq!((t[2].line, t[2].column), (2, 9));
        let e = LexRules::CONCRETE.lex("x = 1.").unwrap_err();
        assert_eq!(
            (e.line, e.column, e.expected.as_str()),
            (1, 7, "a digit after `.`")
        );
        let e = LexRules::ABSTRACT.lex("\"no strings\"").unwrap_err();
        assert_eq!(e.expected, "a name, number or punctuation");
        let e = LexRules::CONCRETE.lex("joint ü").unwrap_err();
        assert_eq!((e.column, e.found.as_str()), (7, "`ü`"));
        assert!(LexRules::ABSTRACT.lex("joint ü").is_ok());
    }
}
