//! Syntax of an `.af` file: blocks of `key value, value, ...` entries.
//!
//! The grammar, which covers Doom 3's files and our extensions alike:
//!
//! ```text
//! file    = block*
//! block   = KIND header* "{" (block* | entry*) "}"     // blocks nest only in containers
//! header  = STRING | NUMBER | IDENT                     // body "name", variant 2 "name"
//! entry   = KEY value ("," value)*
//! value   = NUMBER | STRING | IDENT | IDENT "(" list ")" | "(" list ")"
//! list    = (value ","?)*                               // Doom 3 matrices omit commas
//! ```
//!
//! The containers are `articulatedFigure` (real id files wrap everything in one) and
//! our `variant`. What each key means is decided later, in [`super::build`]; this
//! module only keeps every value with its position for the error messages.

use super::AfError;
use crate::scene::lexer::{Cursor, Pos, Tok, Token};

/// A value after a key, with where it starts.
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    /// A number.
    Num(f64, Pos),
    /// A quoted string.
    Str(String, Pos),
    /// A bare word (`corpse`, `orientation`).
    Ident(String, Pos),
    /// A parenthesised list: a vector `( x, y, z )` or a matrix of them.
    Group(Vec<Value>, Pos),
    /// A function form: `box( ... )`, `joint( "name" )`, `bonecenter( "a", "b" )`.
    Call(String, Vec<Value>, Pos),
}

impl Value {
    /// Where the value starts.
    pub fn pos(&self) -> Pos {
        match self {
            Value::Num(_, p)
            | Value::Str(_, p)
            | Value::Ident(_, p)
            | Value::Group(_, p)
            | Value::Call(_, _, p) => *p,
        }
    }

    /// How the value reads in an error message.
    pub fn describe(&self) -> String {
        match self {
            Value::Num(n, _) => format!("the number {n}"),
            Value::Str(s, _) => format!("the string \"{s}\""),
            Value::Ident(s, _) => format!("the word `{s}`"),
            Value::Group(v, _) => format!("a ( ... ) list of {} values", v.len()),
            Value::Call(name, _, _) => format!("`{name}( ... )`"),
        }
    }
}

/// `key value, value, ...`.
#[derive(Clone, Debug, PartialEq)]
pub struct Entry {
    /// The key as written.
    pub key: String,
    /// Where the key starts.
    pub pos: Pos,
    /// Its values, at least one.
    pub values: Vec<Value>,
}

/// `KIND header* { ... }`.
#[derive(Clone, Debug, PartialEq)]
pub struct Block {
    /// `settings`, `body`, `hinge`, `variant`, ...
    pub kind: String,
    /// Where the kind word starts.
    pub pos: Pos,
    /// The words between the kind and `{`.
    pub header: Vec<Value>,
    /// Entries (for non-containers).
    pub entries: Vec<Entry>,
    /// Nested blocks (for containers).
    pub children: Vec<Block>,
}

impl Block {
    /// The block's quoted or bare name, if its header has one.
    pub fn name(&self) -> Option<(&str, Pos)> {
        self.header.iter().find_map(|v| match v {
            Value::Str(s, p) | Value::Ident(s, p) => Some((s.as_str(), *p)),
            _ => None,
        })
    }
}

/// Every block kind: Doom 3's and ours.
const KINDS: [&str; 14] = [
    "articulatedFigure",
    "settings",
    "body",
    "ballAndSocketJoint",
    "universalJoint",
    "hinge",
    "spring",
    "slider",
    "fixed",
    "variant",
    "ground",
    "camera",
    "transform",
    "replicate",
];

/// Block kinds whose contents are blocks, not entries.
fn is_container(kind: &str) -> bool {
    kind.eq_ignore_ascii_case("articulatedFigure") || kind.eq_ignore_ascii_case("variant")
}

/// Parses tokens into blocks.
pub fn parse(tokens: &[Token], file: &str) -> Result<Vec<Block>, AfError> {
    let mut p = Parser {
        c: Cursor::new(tokens, file),
    };
    let mut blocks = Vec::new();
    while p.c.peek().tok != Tok::Eof {
        blocks.push(p.block(0)?);
    }
    Ok(blocks)
}

struct Parser<'a> {
    c: Cursor<'a>,
}

/// Nesting deeper than this is certainly a mistake; the limit keeps a hostile file from
/// overflowing the stack.
const MAX_DEPTH: usize = 16;

impl<'a> Parser<'a> {
    fn err(&self, pos: Pos, message: String) -> AfError {
        AfError::at(self.c.file(), pos, message)
    }

    /// "expected `what`, found …" at the next token.
    fn expected(&self, what: &str) -> AfError {
        self.c.unexpected(self.c.peek(), what)
    }

    fn block(&mut self, depth: usize) -> Result<Block, AfError> {
        if depth > MAX_DEPTH {
            return Err(self.expected("fewer nested blocks"));
        }
        let t = self.c.next();
        let Tok::Ident(kind) = &t.tok else {
            self.c.back(t);
            return Err(self.expected(
                "a block such as `settings {`, `body \"name\" {` or `hinge \"name\" {`",
            ));
        };
        let (kind, pos) = (kind.clone(), t.pos);
        if !KINDS.iter().any(|k| k.eq_ignore_ascii_case(&kind)) {
            // A block opens with a name or `{`; anything else suggests a key that an
            // extra `}` has pushed out of its block.
            let hint = match self.c.peek().tok {
                Tok::Str(_) | Tok::LBrace => "",
                _ => " (is it a key after an extra `}` that closed its block too soon?)",
            };
            return Err(self.err(
                pos,
                format!(
                    "`{kind}` is not a block; expected one of {}{hint}",
                    KINDS.join(", ")
                ),
            ));
        }
        let mut header = Vec::new();
        loop {
            let t = self.c.peek();
            match &t.tok {
                Tok::LBrace => {
                    self.c.next();
                    break;
                }
                Tok::Str(s) => header.push(Value::Str(s.clone(), t.pos)),
                Tok::Ident(s) => header.push(Value::Ident(s.clone(), t.pos)),
                Tok::Num(n) => header.push(Value::Num(*n, t.pos)),
                _ => return Err(self.expected(&format!("`{{` to open the `{kind}` block"))),
            }
            if header.len() > 3 {
                return Err(self.expected(&format!("`{{` to open the `{kind}` block")));
            }
            self.c.next();
        }
        let mut block = Block {
            kind,
            pos,
            header,
            entries: Vec::new(),
            children: Vec::new(),
        };
        let container = is_container(&block.kind);
        loop {
            let t = self.c.peek();
            match &t.tok {
                Tok::RBrace => {
                    self.c.next();
                    return Ok(block);
                }
                Tok::Eof => {
                    return Err(self.err(
                        t.pos,
                        format!(
                            "the file ends inside the `{}` block opened at line {}; expected `}}`",
                            block.kind, block.pos.line
                        ),
                    ));
                }
                Tok::Ident(_) if container => block.children.push(self.block(depth + 1)?),
                Tok::Ident(key) => {
                    self.c.next();
                    let values = self.values(key, depth)?;
                    block.entries.push(Entry {
                        key: key.clone(),
                        pos: t.pos,
                        values,
                    });
                }
                _ if container => return Err(self.expected("a block or `}`")),
                _ => {
                    return Err(
                        self.expected(&format!("a key or `}}` closing the `{}` block", block.kind))
                    );
                }
            }
        }
    }

    /// A key's values: separated by commas, as id's files write them, or numbers by
    /// blanks alone, as the seed writes `suspendSpeed 20 30 40 60` (a key is never a
    /// number, so a number cannot start the next entry).
    fn values(&mut self, key: &str, depth: usize) -> Result<Vec<Value>, AfError> {
        let mut values = vec![self.value(key, depth)?];
        loop {
            match self.c.peek().tok {
                Tok::Comma => {
                    self.c.next();
                }
                Tok::Num(_) => {}
                _ => return Ok(values),
            }
            values.push(self.value(key, depth)?);
        }
    }

    fn value(&mut self, key: &str, depth: usize) -> Result<Value, AfError> {
        if depth > MAX_DEPTH {
            return Err(self.expected("fewer nested parentheses"));
        }
        let t = self.c.peek();
        let v = match &t.tok {
            Tok::Num(n) => Value::Num(*n, t.pos),
            Tok::Str(s) => Value::Str(s.clone(), t.pos),
            Tok::Ident(s) => {
                self.c.next();
                if self.c.peek().tok == Tok::LParen {
                    self.c.next();
                    let list = self.list(key, depth)?;
                    return Ok(Value::Call(s.clone(), list, t.pos));
                }
                return Ok(Value::Ident(s.clone(), t.pos));
            }
            Tok::LParen => {
                self.c.next();
                let list = self.list(key, depth)?;
                return Ok(Value::Group(list, t.pos));
            }
            _ => return Err(self.expected(&format!("a value for `{key}`"))),
        };
        self.c.next();
        Ok(v)
    }

    /// The inside of `( ... )` up to and including `)`; commas are optional separators.
    fn list(&mut self, key: &str, depth: usize) -> Result<Vec<Value>, AfError> {
        let mut out = Vec::new();
        loop {
            match self.c.peek().tok {
                Tok::RParen => {
                    self.c.next();
                    return Ok(out);
                }
                Tok::Comma if !out.is_empty() => {
                    self.c.next();
                }
                Tok::Eof | Tok::LBrace | Tok::RBrace => {
                    return Err(self.expected(&format!("`)` closing a list in `{key}`")));
                }
                _ => out.push(self.value(key, depth + 1)?),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::lexer::tokenize;

    fn parse_str(s: &str) -> Result<Vec<Block>, AfError> {
        parse(&tokenize(s, "t.af")?, "t.af")
    }

    #[test]
    fn entries_keep_values_and_positions() {
        let b = parse_str(
            "body \"a\" {\n model box( (-1, -1, -1), (1, 1, 1) )\n clipMask solid, corpse\n}",
        )
        .unwrap();
        assert_eq!(b.len(), 1);
        assert_eq!(b[0].name().unwrap().0, "a");
        assert_eq!(b[0].entries.len(), 2);
        assert!(
            matches!(&b[0].entries[0].values[0], Value::Call(n, args, _) if n == "box" && args.len() == 2)
        );
        assert_eq!(b[0].entries[1].values.len(), 2);
        assert_eq!(b[0].entries[1].pos, Pos { line: 3, col: 2 });
    }

    #[test]
    fn containers_hold_blocks() {
        let b = parse_str("articulatedFigure x { settings { totalMass 5 } variant 2 \"v\" { settings { iterations 2 } } }").unwrap();
        assert_eq!(b[0].children.len(), 2);
        assert_eq!(b[0].children[1].children.len(), 1);
    }

    #[test]
    fn truncated_block_names_its_opening_line() {
        let e = parse_str("settings {\n totalMass 5\n").unwrap_err();
        assert!(e.message.contains("opened at line 1"), "{e}");
        assert_eq!(e.line, 3);
    }

    #[test]
    fn deep_nesting_is_an_error_not_a_stack_overflow() {
        let s = format!("settings {{ x {} }}", "(".repeat(10_000));
        assert!(parse_str(&s).is_err());
    }
}
