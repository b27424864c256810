//! A first pass over model text, before `proc_macro2` lexes it.
//!
//! `proc_macro2`'s lexer answers every problem with the same "cannot parse
//! string into token stream". This pass finds the problems a model file
//! actually has — an unbalanced bracket, a character Rust does not lex, a
//! NUL byte, an unterminated string or comment, brackets nested deeper than
//! any expression may be — and says which one, where. It mirrors the parts
//! of Rust's lexer that decide whether text splits into tokens at all;
//! whether the tokens make a model is the parser's business.
//!
//! Positions are 1-based lines and columns counted in characters, as
//! `proc_macro2` counts them.

use std::fmt;

/// Why model text cannot be split into tokens.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum LexError {
    /// An opening bracket that is never closed.
    Unclosed {
        /// `(`, `[` or `{`.
        open: char,
        /// Where it was opened.
        at: Pos,
    },
    /// A closing bracket with nothing open.
    Unexpected {
        /// `)`, `]` or `}`.
        close: char,
        /// Where.
        at: Pos,
    },
    /// A closing bracket of the wrong kind.
    Mismatched {
        /// The closing bracket found.
        close: char,
        /// Where.
        at: Pos,
        /// The bracket it would have to close.
        open: char,
        /// Where that was opened.
        opened: Pos,
    },
    /// A character that is no part of any token.
    Character {
        /// The character.
        ch: char,
        /// Where.
        at: Pos,
    },
    /// A NUL byte.
    Nul {
        /// Where.
        at: Pos,
    },
    /// A string literal without its closing quote.
    UnterminatedString {
        /// Where it starts.
        at: Pos,
    },
    /// A character literal without its closing quote.
    UnterminatedChar {
        /// Where it starts.
        at: Pos,
    },
    /// A `/* … */` comment without its `*/`.
    UnterminatedComment {
        /// Where it starts.
        at: Pos,
    },
    /// Brackets nested deeper than any expression may be.
    TooDeep {
        /// The expression nesting limit ([`crate::dsl::MAX_DEPTH`]).
        limit: usize,
        /// The bracket that goes past it.
        at: Pos,
    },
}

/// A position in the text: 1-based line and column (in characters).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pos {
    /// Line, from 1.
    pub line: usize,
    /// Column, from 1, in characters.
    pub column: usize,
}

impl fmt::Display for Pos {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}", self.line, self.column)
    }
}

fn closer(open: char) -> char {
    match open {
        '(' => ')',
        '[' => ']',
        _ => '}',
    }
}

impl LexError {
    /// Where the problem is (for an unclosed bracket: the bracket).
    pub fn pos(&self) -> Pos {
        match self {
            LexError::Unclosed { at, .. }
            | LexError::Unexpected { at, .. }
            | LexError::Mismatched { at, .. }
            | LexError::Character { at, .. }
            | LexError::Nul { at }
            | LexError::UnterminatedString { at }
            | LexError::UnterminatedChar { at }
            | LexError::UnterminatedComment { at }
            | LexError::TooDeep { at, .. } => *at,
        }
    }

    /// The message without the position [`LexError::pos`] (for an error
    /// that carries the position in its span).
    pub fn message(&self) -> String {
        match self {
            LexError::Unclosed { open, .. } => format!(
                "unclosed `{open}`: the text ends before its `{}`",
                closer(*open)
            ),
            LexError::Unexpected { close, .. } => {
                format!("unexpected `{close}`: no bracket is open here")
            }
            LexError::Mismatched {
                close,
                open,
                opened,
                ..
            } => format!(
                "`{close}` does not close the `{open}` opened at {opened} (expected `{}`)",
                closer(*open)
            ),
            LexError::Character { ch, .. } => {
                format!("character {ch:?} (U+{:04X}) not allowed", *ch as u32)
            }
            LexError::Nul { .. } => "NUL byte not allowed".to_string(),
            LexError::UnterminatedString { .. } => {
                "unterminated string: no closing `\"`".to_string()
            }
            LexError::UnterminatedChar { .. } => {
                "unterminated character literal: no closing `'`".to_string()
            }
            LexError::UnterminatedComment { .. } => {
                "unterminated comment: no closing `*/`".to_string()
            }
            LexError::TooDeep { limit, .. } => {
                format!("expression nested too deep (limit {limit})")
            }
        }
    }
}

impl fmt::Display for LexError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LexError::Unclosed { open, at } => write!(f, "unclosed `{open}` opened at {at}"),
            LexError::UnterminatedString { at } => {
                write!(f, "unterminated string starting at {at}")
            }
            LexError::UnterminatedChar { at } => {
                write!(f, "unterminated character literal starting at {at}")
            }
            LexError::UnterminatedComment { at } => {
                write!(f, "unterminated comment starting at {at}")
            }
            other => write!(f, "{} at {}", other.message(), other.pos()),
        }
    }
}

impl std::error::Error for LexError {}

/// A cursor over the text that tracks line and column.
struct Cursor<'a> {
    chars: std::iter::Peekable<std::str::Chars<'a>>,
    pos: Pos,
}

impl Cursor<'_> {
    fn peek(&mut self) -> Option<char> {
        self.chars.peek().copied()
    }

    /// The character after the next one.
    fn peek2(&self) -> Option<char> {
        let mut it = self.chars.clone();
        it.next();
        it.next()
    }

    fn bump(&mut self) -> Option<char> {
        let c = self.chars.next()?;
        if c == '\n' {
            self.pos.line += 1;
            self.pos.column = 1;
        } else {
            self.pos.column += 1;
        }
        Some(c)
    }

    fn eat(&mut self, c: char) -> bool {
        if self.peek() == Some(c) {
            self.bump();
            true
        } else {
            false
        }
    }
}

/// Whitespace as Rust's lexer has it.
fn is_whitespace(c: char) -> bool {
    c.is_whitespace() || c == '\u{200e}' || c == '\u{200f}'
}

fn is_ident_start(c: char) -> bool {
    c == '_' || unicode_ident::is_xid_start(c)
}

fn is_ident_continue(c: char) -> bool {
    unicode_ident::is_xid_continue(c)
}

/// Punctuation Rust lexes as a token.
const PUNCT: &str = "~!@#$%^&*-=+|;:,<.>/?";

/// Check that `src` splits into tokens with balanced brackets nested at most
/// `max_brackets` deep. `depth_limit` is the expression nesting limit named
/// in the error.
pub fn scan(src: &str, max_brackets: usize, depth_limit: usize) -> Result<(), LexError> {
    let mut c = Cursor {
        chars: src.chars().peekable(),
        pos: Pos { line: 1, column: 1 },
    };
    let mut open: Vec<(char, Pos)> = Vec::new();
    while let Some(ch) = c.peek() {
        let at = c.pos;
        match ch {
            '\0' => return Err(LexError::Nul { at }),
            '/' if c.peek2() == Some('/') => {
                while c.peek().is_some_and(|x| x != '\n') {
                    if c.bump() == Some('\0') {
                        // Rust's lexer accepts a NUL in a comment, but the
                        // stress tests show it is never intended.
                        return Err(LexError::Nul { at: c.pos_before() });
                    }
                }
            }
            '/' if c.peek2() == Some('*') => block_comment(&mut c, at)?,
            '(' | '[' | '{' => {
                c.bump();
                if open.len() == max_brackets {
                    return Err(LexError::TooDeep {
                        limit: depth_limit,
                        at,
                    });
                }
                open.push((ch, at));
            }
            ')' | ']' | '}' => {
                c.bump();
                match open.pop() {
                    None => return Err(LexError::Unexpected { close: ch, at }),
                    Some((o, opened)) if closer(o) != ch => {
                        return Err(LexError::Mismatched {
                            close: ch,
                            at,
                            open: o,
                            opened,
                        })
                    }
                    Some(_) => {}
                }
            }
            '"' => {
                c.bump();
                quoted(&mut c, at)?;
            }
            '\'' => {
                c.bump();
                char_or_lifetime(&mut c, at)?;
            }
            _ if is_whitespace(ch) => {
                c.bump();
            }
            _ if is_ident_start(ch) || ch.is_ascii_digit() => word(&mut c, at)?,
            _ if PUNCT.contains(ch) => {
                c.bump();
            }
            _ => return Err(LexError::Character { ch, at }),
        }
    }
    match open.pop() {
        Some((o, at)) => Err(LexError::Unclosed { open: o, at }),
        None => Ok(()),
    }
}

impl Cursor<'_> {
    /// Position of the character just consumed (not across a newline).
    fn pos_before(&self) -> Pos {
        Pos {
            line: self.pos.line,
            column: self.pos.column.saturating_sub(1).max(1),
        }
    }
}

/// `/* … */`, nested as in Rust; the cursor is on the `/`.
fn block_comment(c: &mut Cursor<'_>, at: Pos) -> Result<(), LexError> {
    c.bump();
    c.bump();
    let mut depth = 1usize;
    while depth > 0 {
        match c.bump() {
            None => return Err(LexError::UnterminatedComment { at }),
            Some('/') if c.eat('*') => depth += 1,
            Some('*') if c.eat('/') => depth -= 1,
            Some(_) => {}
        }
    }
    Ok(())
}

/// The rest of a `"…"` string after its opening quote (escapes skipped).
fn quoted(c: &mut Cursor<'_>, at: Pos) -> Result<(), LexError> {
    loop {
        match c.bump() {
            None => return Err(LexError::UnterminatedString { at }),
            Some('"') => return Ok(()),
            Some('\\') => {
                c.bump();
            }
            Some(_) => {}
        }
    }
}

/// The rest of a raw string `r#…#"…"#…#` after the `r`.
fn raw_string(c: &mut Cursor<'_>, at: Pos) -> Result<(), LexError> {
    let mut hashes = 0usize;
    while c.eat('#') {
        hashes += 1;
    }
    if !c.eat('"') {
        // `r#` followed by something else: a raw identifier (or an error
        // the token lexer reports).
        return Ok(());
    }
    loop {
        match c.bump() {
            None => return Err(LexError::UnterminatedString { at }),
            Some('"') => {
                let mut n = 0;
                while n < hashes && c.eat('#') {
                    n += 1;
                }
                if n == hashes {
                    return Ok(());
                }
            }
            Some(_) => {}
        }
    }
}

/// After a `'`: a character literal `'x'`, `'\n'` or a lifetime `'a`.
fn char_or_lifetime(c: &mut Cursor<'_>, at: Pos) -> Result<(), LexError> {
    match c.peek() {
        Some('\\') => {
            c.bump();
            c.bump();
            // `'\u{…}'`: skip to the closing quote on this line.
            while let Some(x) = c.peek() {
                if x == '\'' || x == '\n' {
                    break;
                }
                c.bump();
            }
            if c.eat('\'') {
                Ok(())
            } else {
                Err(LexError::UnterminatedChar { at })
            }
        }
        Some(x) if x != '\n' && x != '\'' => {
            if c.peek2() == Some('\'') {
                c.bump();
                c.bump();
                return Ok(());
            }
            if is_ident_start(x) {
                // A lifetime.
                while c.peek().is_some_and(is_ident_continue) {
                    c.bump();
                }
                return Ok(());
            }
            Err(LexError::UnterminatedChar { at })
        }
        _ => Err(LexError::UnterminatedChar { at }),
    }
}

/// An identifier, keyword, number, or a prefixed literal (`r"…"`, `b"…"`,
/// `b'x'`); the cursor is on its first character.
fn word(c: &mut Cursor<'_>, at: Pos) -> Result<(), LexError> {
    let mut text = String::new();
    while let Some(x) = c.peek() {
        if is_ident_continue(x) {
            text.push(x);
            c.bump();
        } else if x == '.' && text.starts_with(|d: char| d.is_ascii_digit()) {
            // `1.5`, but not `1..2` or `1.max`.
            match c.peek2() {
                Some(d) if d.is_ascii_digit() => {
                    text.push('.');
                    c.bump();
                }
                _ => break,
            }
        } else {
            break;
        }
    }
    match (text.as_str(), c.peek()) {
        ("r" | "br" | "cr", Some('"' | '#')) => raw_string(c, at),
        ("b" | "c", Some('"')) => {
            c.bump();
            quoted(c, at)
        }
        ("b", Some('\'')) => {
            c.bump();
            char_or_lifetime(c, at)
        }
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(src: &str) -> String {
        scan(src, 10, 8).unwrap_err().to_string()
    }

    #[test]
    fn every_problem_has_its_place() {
        assert_eq!(err("a {\n  b { c }\n"), "unclosed `{` opened at 1:3");
        assert_eq!(
            err("a { b }\n}"),
            "unexpected `}`: no bracket is open here at 2:1"
        );
        assert_eq!(
            err("a ( b ]"),
            "`]` does not close the `(` opened at 1:3 (expected `)`) at 1:7"
        );
        assert_eq!(
            err("x\n  y 😀 z"),
            "character '😀' (U+1F600) not allowed at 2:5"
        );
        assert_eq!(err("ab\0c"), "NUL byte not allowed at 1:3");
        assert_eq!(
            err("a\n  \"abc\n\n d"),
            "unterminated string starting at 2:3"
        );
        assert_eq!(err("x /* y /* */"), "unterminated comment starting at 1:3");
        assert_eq!(err("a ` b"), "character '`' (U+0060) not allowed at 1:3");
        assert_eq!(
            err("a \\ b"),
            "character '\\\\' (U+005C) not allowed at 1:3"
        );
        assert_eq!(
            err("((((((((((( x"),
            "expression nested too deep (limit 8) at 1:11"
        );
    }

    #[test]
    fn what_rust_lexes_passes() {
        for ok in [
            "pub M { a = 1.5e-3; b = x^2 / 3 }",
            "/// doc \"quoted\"\nM { } // } comment (\n/* nested /* } */ */",
            "é λ x 'a 'b' '\\n' b'x' b\"s\" r#\"raw \" str\"# r#type",
            "1..2 1.max 1.5f64 0x1F",
        ] {
            assert_eq!(scan(ok, 10, 8), Ok(()), "{ok}");
        }
    }
}
