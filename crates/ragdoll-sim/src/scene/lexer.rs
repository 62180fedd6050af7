//! Tokens of Doom 3's text formats, each with its line and column: the one lexer of the
//! `.af`, `.md5mesh`, `.md5anim` and `.def` readers.
//!
//! The syntax is idLexer's: C-style `//` and `/* */` comments, double-quoted strings
//! (no escapes; `"a" \ "b"` concatenates), numbers, identifiers (letters, digits, `_`, and `*`/`-`/`.` inside
//! names that real files use in bare words, and `/`, `\`, `:` inside the bare paths of
//! `.def` files), and the punctuation `{ } ( ) ,`. Newlines carry no meaning. A UTF-8
//! byte-order mark at the start is skipped (idLexer reads it as whitespace).

use super::file_error::AfError;

/// Where a token starts: 1-based line and column (columns count characters).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Pos {
    /// 1-based line.
    pub line: u32,
    /// 1-based column.
    pub col: u32,
}

/// What a token is.
#[derive(Clone, Debug, PartialEq)]
pub enum Tok {
    /// A bare word: a keyword, key or function name.
    Ident(String),
    /// A double-quoted string, without the quotes.
    Str(String),
    /// A number (Doom 3 writes integers and decimals, optionally signed).
    Num(f64),
    /// `{`
    LBrace,
    /// `}`
    RBrace,
    /// `(`
    LParen,
    /// `)`
    RParen,
    /// `,`
    Comma,
    /// End of the text.
    Eof,
}

impl Tok {
    /// How the token reads in an error message.
    pub fn describe(&self) -> String {
        match self {
            Tok::Ident(s) => format!("`{s}`"),
            Tok::Str(s) => format!("string \"{s}\""),
            Tok::Num(n) => format!("number {n}"),
            Tok::LBrace => "`{`".into(),
            Tok::RBrace => "`}`".into(),
            Tok::LParen => "`(`".into(),
            Tok::RParen => "`)`".into(),
            Tok::Comma => "`,`".into(),
            Tok::Eof => "the end of the file".into(),
        }
    }
}

/// A token and where it starts.
#[derive(Clone, Debug, PartialEq)]
pub struct Token {
    /// The token.
    pub tok: Tok,
    /// Its position.
    pub pos: Pos,
}

/// A read position in a token list from [`tokenize`], shared by the `.af` parser and
/// the md5mesh reader so both report "expected X, found Y" the same way.
pub(crate) struct Cursor<'a> {
    tokens: &'a [Token],
    i: usize,
    file: &'a str,
}

impl<'a> Cursor<'a> {
    /// A cursor at the first of `tokens` (which end with [`Tok::Eof`]) of `file`.
    pub(crate) fn new(tokens: &'a [Token], file: &'a str) -> Cursor<'a> {
        Cursor { tokens, i: 0, file }
    }

    /// The file the tokens come from, for error positions.
    pub(crate) fn file(&self) -> &'a str {
        self.file
    }

    /// The next token, not consumed. The list ends with Eof and [`Cursor::next`] never
    /// moves past it, so there is always one.
    pub(crate) fn peek(&self) -> &'a Token {
        &self.tokens[self.i.min(self.tokens.len().saturating_sub(1))]
    }

    /// Consumes and returns the next token (Eof stays put).
    pub(crate) fn next(&mut self) -> &'a Token {
        let t = self.peek();
        if t.tok != Tok::Eof {
            self.i += 1;
        }
        t
    }

    /// Un-reads the token `next` just returned, so an error can point at it.
    pub(crate) fn back(&mut self, t: &Token) {
        if t.tok != Tok::Eof {
            self.i -= 1;
        }
    }

    /// "expected `what`, found …" at token `t`.
    pub(crate) fn unexpected(&self, t: &Token, what: &str) -> AfError {
        AfError::at(
            self.file,
            t.pos,
            format!("expected {what}, found {}", t.tok.describe()),
        )
    }
}

/// Splits `text` into tokens, ending with [`Tok::Eof`].
pub fn tokenize(text: &str, file: &str) -> Result<Vec<Token>, AfError> {
    tokenize_from(text, file, Pos { line: 1, col: 1 })
}

/// Splits `text`, which starts at `start` of `file`, into tokens ending with
/// [`Tok::Eof`]; positions are in the whole file (a `.def` reader tokenizes one
/// declaration at a time).
pub(crate) fn tokenize_from(text: &str, file: &str, start: Pos) -> Result<Vec<Token>, AfError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let chars: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let (mut i, mut line, mut col) = (0usize, start.line, start.col);
    let err = |pos: Pos, message: String| AfError::at(file, pos, message);
    // Advances over one character, keeping line and column.
    macro_rules! bump {
        () => {{
            if chars[i] == '\n' {
                line += 1;
                col = 1;
            } else {
                col += 1;
            }
            i += 1;
        }};
    }
    while i < chars.len() {
        let c = chars[i];
        let pos = Pos { line, col };
        if c.is_whitespace() {
            bump!();
            continue;
        }
        if c == '/' && chars.get(i + 1) == Some(&'/') {
            while i < chars.len() && chars[i] != '\n' {
                bump!();
            }
            continue;
        }
        if c == '/' && chars.get(i + 1) == Some(&'*') {
            bump!();
            bump!();
            loop {
                if i >= chars.len() {
                    return Err(err(
                        pos,
                        "this `/*` comment is never closed with `*/`".into(),
                    ));
                }
                if chars[i] == '*' && chars.get(i + 1) == Some(&'/') {
                    bump!();
                    bump!();
                    break;
                }
                bump!();
            }
            continue;
        }
        let single = match c {
            '{' => Some(Tok::LBrace),
            '}' => Some(Tok::RBrace),
            '(' => Some(Tok::LParen),
            ')' => Some(Tok::RParen),
            ',' => Some(Tok::Comma),
            _ => None,
        };
        if let Some(tok) = single {
            bump!();
            out.push(Token { tok, pos });
            continue;
        }
        if c == '"' {
            bump!();
            let mut s = String::new();
            loop {
                match chars.get(i) {
                    None => return Err(err(pos, "this string is never closed with `\"`".into())),
                    Some('\n') => {
                        return Err(err(
                            pos,
                            "this string runs to the end of the line; close it with `\"`".into(),
                        ));
                    }
                    Some('"') => {
                        bump!();
                        // `"a" \ "b"` is one string "ab" (idLexer's backslash string
                        // concatenation, which .def files use for long values).
                        let mut j = i;
                        while chars.get(j).is_some_and(|c| c.is_whitespace()) {
                            j += 1;
                        }
                        if chars.get(j) != Some(&'\\') {
                            break;
                        }
                        let mut k = j + 1;
                        while chars.get(k).is_some_and(|c| c.is_whitespace()) {
                            k += 1;
                        }
                        if chars.get(k) != Some(&'"') {
                            break;
                        }
                        while i <= k {
                            bump!();
                        }
                    }
                    Some(&ch) => {
                        s.push(ch);
                        bump!();
                    }
                }
            }
            out.push(Token {
                tok: Tok::Str(s),
                pos,
            });
            continue;
        }
        let starts_number = c.is_ascii_digit()
            || ((c == '-' || c == '+' || c == '.')
                && chars
                    .get(i + 1)
                    .is_some_and(|d| d.is_ascii_digit() || *d == '.'));
        if starts_number {
            let start = i;
            bump!();
            while i < chars.len() {
                let d = chars[i];
                let exp_sign = (d == '-' || d == '+') && matches!(chars[i - 1], 'e' | 'E');
                if d.is_ascii_digit() || d == '.' || d == 'e' || d == 'E' || exp_sign {
                    bump!();
                } else {
                    break;
                }
            }
            let s: String = chars[start..i].iter().collect();
            let n: f64 = s
                .parse()
                .map_err(|_| err(pos, format!("`{s}` is not a number")))?;
            out.push(Token {
                tok: Tok::Num(n),
                pos,
            });
            continue;
        }
        // A name may start with `-` where a .def names joints to leave out (`-*Waist`).
        let minus_name = c == '-'
            && chars
                .get(i + 1)
                .is_some_and(|d| d.is_alphabetic() || matches!(d, '_' | '*'));
        if c.is_alphabetic() || c == '_' || c == '*' || minus_name {
            let start = i;
            // `/` continues a bare path unless it opens a comment.
            let continues = |i: usize| {
                let c = chars[i];
                c.is_alphanumeric()
                    || matches!(c, '_' | '*' | '.' | '-' | '\\' | ':')
                    || (c == '/' && !matches!(chars.get(i + 1), Some('/' | '*')))
            };
            while i < chars.len() && continues(i) {
                bump!();
            }
            let s: String = chars[start..i].iter().collect();
            out.push(Token {
                tok: Tok::Ident(s),
                pos,
            });
            continue;
        }
        return Err(err(pos, format!("unexpected character `{c}`")));
    }
    out.push(Token {
        tok: Tok::Eof,
        pos: Pos { line, col },
    });
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn positions_count_lines_and_columns() {
        let t = tokenize("body \"a\" {\n  origin ( 1, -2.5e1, .5 ) // c\n}", "f").unwrap();
        assert_eq!(t[0].tok, Tok::Ident("body".into()));
        assert_eq!(t[1].tok, Tok::Str("a".into()));
        assert_eq!(t[3].pos, Pos { line: 2, col: 3 });
        assert_eq!(t[7].tok, Tok::Num(-25.0));
        assert_eq!(t[9].tok, Tok::Num(0.5));
        assert_eq!(t.last().unwrap().tok, Tok::Eof);
    }

    #[test]
    fn bare_paths_byte_order_mark_and_offsets() {
        let t = tokenize("\u{feff}mesh models/md5/a.md5mesh// c\nx", "f").unwrap();
        assert_eq!(t[0].pos, Pos { line: 1, col: 1 });
        assert_eq!(t[1].tok, Tok::Ident("models/md5/a.md5mesh".into()));
        assert_eq!(t[2].tok, Tok::Ident("x".into()));
        let t = tokenize("\"ab\" \\\n\t\"cd\" x", "f").unwrap();
        assert_eq!(t[0].tok, Tok::Str("abcd".into()));
        assert_eq!(t[1].pos, Pos { line: 2, col: 7 });
        let t = tokenize("( *a -*b )", "f").unwrap();
        assert_eq!(t[2].tok, Tok::Ident("-*b".into()));
        let t = tokenize_from("a\n b", "f", Pos { line: 5, col: 7 }).unwrap();
        assert_eq!(t[0].pos, Pos { line: 5, col: 7 });
        assert_eq!(t[1].pos, Pos { line: 6, col: 2 });
    }

    #[test]
    fn control_characters_are_escaped_in_messages() {
        let e = tokenize("a \u{1}", "f").unwrap_err();
        assert!(!e.message.chars().any(char::is_control), "{}", e.message);
        assert!(e.message.contains("\\u{1}"), "{}", e.message);
    }

    #[test]
    fn unclosed_string_is_an_error_at_its_start() {
        let e = tokenize("x \"abc", "f").unwrap_err();
        assert_eq!((e.line, e.col), (1, 3));
    }
}
