//! A text fuzzer for the readers: mutations on char boundaries (truncate, delete a run,
//! insert or substitute one of a reader's own tokens, duplicate a line), so a mutated
//! file stays close enough to the format to reach deep into its reader.

use proptest::prelude::*;

#[derive(Debug, Clone)]
pub enum Mutation {
    Truncate(usize),
    Delete(usize, usize),
    /// Insert token `.1` at `.0`.
    Insert(usize, usize),
    /// Replace the word at `.0` with token `.1`.
    Replace(usize, usize),
    DuplicateLine(usize),
}

/// Any mutation, over `tokens` tokens.
pub fn strategy(tokens: usize) -> impl Strategy<Value = Mutation> {
    prop_oneof![
        any::<usize>().prop_map(Mutation::Truncate),
        (any::<usize>(), 1usize..40).prop_map(|(a, n)| Mutation::Delete(a, n)),
        (any::<usize>(), 0..tokens).prop_map(|(a, t)| Mutation::Insert(a, t)),
        (any::<usize>(), 0..tokens).prop_map(|(a, t)| Mutation::Replace(a, t)),
        any::<usize>().prop_map(Mutation::DuplicateLine),
    ]
}

/// Applies mutations on char boundaries, with `tokens` the reader's own words.
pub fn apply(text: &str, muts: &[Mutation], tokens: &[&str]) -> String {
    let mut chars: Vec<char> = text.chars().collect();
    for m in muts {
        let len = chars.len().max(1);
        match *m {
            Mutation::Truncate(a) => chars.truncate(a % len),
            Mutation::Delete(a, n) => {
                let s = a % len;
                let e = (s + n).min(chars.len());
                if s < e {
                    chars.drain(s..e);
                }
            }
            Mutation::Insert(a, t) => {
                let at = a % (chars.len() + 1);
                let ins: Vec<char> = format!(" {} ", tokens[t]).chars().collect();
                chars.splice(at..at, ins);
            }
            Mutation::Replace(a, t) => {
                // Replace the word at `a` with a token.
                let at = a % len;
                let mut e = at;
                while e < chars.len() && !chars[e].is_whitespace() {
                    e += 1;
                }
                chars.splice(at..e, tokens[t].chars());
            }
            Mutation::DuplicateLine(a) => {
                let text: String = chars.iter().collect();
                let lines: Vec<&str> = text.lines().collect();
                if !lines.is_empty() {
                    let i = a % lines.len();
                    let mut out: Vec<&str> = lines.clone();
                    out.insert(i, lines[i]);
                    chars = out.join("\n").chars().collect();
                }
            }
        }
    }
    chars.into_iter().collect()
}
