//! Doom 3 declarations, read far enough to find a character: `entityDef` (its `model`,
//! its figure under `ragdoll` or `articulatedFigure`, `skin`, `inherit`), `model`
//! declarations (`mesh`, `skin`, `offset`, `anim` entries, `inherit`, `remove`) and
//! which `.af` file holds an `articulatedFigure`.
//!
//! The engine's rules (dhewm3 `DeclManager`, `DeclEntityDef`, `Anim_Blend`):
//! - A mod's declarations are in `def/*.def` and `af/*.af` under its base folder, not
//!   recursive, files sorted without regard to case. Any file holds any number of
//!   `type name { ... }`; without a type word a declaration takes the folder's
//!   (`entityDef` in def/, `articulatedFigure` in af/).
//! - Declaration types and names compare without regard to case; a name drops what
//!   follows its last `.` (`x.af` is `x`); `\` reads as `/`. On a duplicate the first
//!   file wins.
//! - Paths are relative to the base folder; file names compare without regard to case.
//! - `entityDef` keys compare without regard to case; a repeated key keeps the last
//!   value. `inherit` keys are removed, each parent resolved fully, then each in order
//!   adds only the keys still missing: the child wins, an earlier parent beats a later.
//! - `model` keywords are case-sensitive; `inherit` copies the parent whole before the
//!   child continues; a redefined `anim` replaces the inherited one, `remove` drops one.
//!
//! Only the declarations asked for are tokenized, so an unrelated declaration the
//! shared lexer cannot read does not stop a lookup.

use super::file_error::{AfError, read_text};
use super::lexer::{Pos, Tok, Token, tokenize_from};
use glam::Vec3;
use std::path::{Path, PathBuf};

/// One declaration found while scanning: where its body is.
#[derive(Clone, Debug)]
struct DeclSource {
    /// Type, lower case.
    kind: String,
    /// Name as Doom 3 keys it: lower case, `/` for `\`, no extension.
    key: String,
    /// Name as written.
    name: String,
    /// The file it is in.
    file: PathBuf,
    /// Byte range of the text between its braces.
    body: std::ops::Range<usize>,
    /// Where that text starts.
    body_pos: Pos,
}

/// A mod's base folder and the declarations in it.
#[derive(Clone, Debug)]
pub struct Doom3Base {
    /// The base folder.
    pub root: PathBuf,
    decls: Vec<DeclSource>,
    /// Files that could not be scanned whole, with why (Doom 3 warns and goes on).
    pub warnings: Vec<String>,
}

/// An `entityDef` with its inheritance resolved.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct EntityDef {
    /// Its name as written.
    pub name: String,
    /// Keys (as first written) and values, `classname` first.
    pub keys: Vec<(String, String)>,
}

impl EntityDef {
    /// The value of `key`, compared without regard to case.
    pub fn get(&self, key: &str) -> Option<&str> {
        self.keys
            .iter()
            .find(|(k, _)| k.eq_ignore_ascii_case(key))
            .map(|(_, v)| v.as_str())
    }

    fn set(&mut self, key: &str, value: &str) {
        match self
            .keys
            .iter_mut()
            .find(|(k, _)| k.eq_ignore_ascii_case(key))
        {
            Some(kv) => kv.1 = value.to_string(),
            None => self.keys.push((key.to_string(), value.to_string())),
        }
    }
}

/// One `anim` entry of a model declaration.
#[derive(Clone, Debug, PartialEq)]
pub struct AnimEntry {
    /// The anim's name (compared exactly, as Doom 3's `GetAnim` does).
    pub name: String,
    /// Its `.md5anim` files, relative to the base folder.
    pub files: Vec<String>,
}

/// A `model` declaration with its inheritance resolved.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct ModelDecl {
    /// Its name as written.
    pub name: String,
    /// The `.md5mesh`, relative to the base folder.
    pub mesh: Option<String>,
    /// The skin.
    pub skin: Option<String>,
    /// Added to the root joint (file units).
    pub offset: Vec3,
    /// The anims in order.
    pub anims: Vec<AnimEntry>,
}

impl ModelDecl {
    /// The anim named exactly `name`.
    pub fn anim(&self, name: &str) -> Option<&AnimEntry> {
        self.anims.iter().find(|a| a.name == name)
    }
}

/// The files a model key names.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct ModelFiles {
    /// The model declaration, when the key names one (else it is a path).
    pub decl: Option<ModelDecl>,
    /// The mesh file.
    pub mesh: Option<PathBuf>,
    /// The `af_pose` animation file, when the declaration has one.
    pub af_pose: Option<PathBuf>,
}

/// What an entity needs to become a ragdoll: the resolved declarations and files.
#[derive(Clone, Debug, PartialEq)]
pub struct Doom3Character {
    /// The entity.
    pub entity: EntityDef,
    /// Its model declaration, when `model` names one.
    pub model: Option<ModelDecl>,
    /// The `.af` file holding the figure.
    pub af_file: PathBuf,
    /// The figure's name in it.
    pub figure: String,
    /// The mesh file, when there is one.
    pub mesh: Option<PathBuf>,
    /// The `af_pose` animation file, when the model has one.
    pub af_pose: Option<PathBuf>,
    /// Every other anim of the model with its first file.
    pub anims: Vec<(String, PathBuf)>,
    /// The skin (the entity's, else the model's).
    pub skin: Option<String>,
}

/// Doom 3's declaration key for a name.
fn decl_key(name: &str) -> String {
    let mut k = name.replace('\\', "/").to_ascii_lowercase();
    if let Some(dot) = k.rfind('.')
        && !k[dot..].contains('/')
    {
        k.truncate(dot);
    }
    k
}

impl Doom3Base {
    /// Scans `root`'s `def/*.def` and `af/*.af`. A base folder without either is an error.
    pub fn open(root: &Path) -> Result<Doom3Base, AfError> {
        let mut base = Doom3Base {
            root: root.to_path_buf(),
            decls: Vec::new(),
            warnings: Vec::new(),
        };
        let mut found_dir = false;
        for (dir, ext, default_kind) in [
            ("def", "def", "entitydef"),
            ("af", "af", "articulatedfigure"),
        ] {
            let Some(d) = resolve_ci(root, dir) else {
                continue;
            };
            found_dir = true;
            let mut files: Vec<PathBuf> = std::fs::read_dir(&d)
                .map_err(|e| io_error(&d, e))?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| {
                    p.is_file() && p.extension().is_some_and(|x| x.eq_ignore_ascii_case(ext))
                })
                .collect();
            files.sort_by_key(|p| {
                p.file_name()
                    .map(|n| n.to_string_lossy().to_ascii_lowercase())
            });
            for f in files {
                let text = read_text(&f, "declaration file")?;
                if let Err(e) = base.scan(&f, &text, default_kind) {
                    base.warnings.push(e.to_string());
                }
            }
        }
        if !found_dir {
            return Err(AfError {
                file: root.display().to_string(),
                line: 1,
                col: 1,
                message: "not a Doom 3 base folder: it has neither def/ nor af/".into(),
            });
        }
        Ok(base)
    }

    /// Finds the declarations in one file: `[type] name { ... }` with balanced braces.
    fn scan(&mut self, file: &Path, text: &str, default_kind: &str) -> Result<(), AfError> {
        let fname = file.display().to_string();
        let mut s = Scanner::new(text);
        loop {
            let mut words: Vec<(String, Pos)> = Vec::new();
            let open = loop {
                s.skip_space(&fname)?;
                let pos = s.pos();
                match s.peek() {
                    None if words.is_empty() => return Ok(()),
                    None => {
                        return Err(AfError::at(
                            &fname,
                            pos,
                            format!("`{}` is not followed by `{{ ... }}`", words[0].0),
                        ));
                    }
                    Some('{') => break pos,
                    Some('}') => {
                        return Err(AfError::at(&fname, pos, "this `}` closes nothing".into()));
                    }
                    Some(_) => words.push((s.word(&fname)?, pos)),
                }
            };
            s.bump();
            let body_start = s.i;
            let body_pos = s.pos();
            s.skip_block(&fname, open)?;
            let body = body_start..s.i - 1;
            let (kind, (name, _)) = match words.len() {
                1 => (default_kind.to_string(), words.pop().expect("one word")),
                2 => {
                    let n = words.pop().expect("two words");
                    (words[0].0.to_ascii_lowercase(), n)
                }
                0 => {
                    return Err(AfError::at(
                        &fname,
                        open,
                        "a declaration needs a name before `{`".into(),
                    ));
                }
                _ => {
                    return Err(AfError::at(
                        &fname,
                        words[2].1,
                        format!("expected `{{` after `{} {}`", words[0].0, words[1].0),
                    ));
                }
            };
            let key = decl_key(&name);
            if !self.decls.iter().any(|d| d.kind == kind && d.key == key) {
                self.decls.push(DeclSource {
                    kind,
                    key,
                    name,
                    file: file.to_path_buf(),
                    body,
                    body_pos,
                });
            }
        }
    }

    fn find(&self, kind: &str, name: &str) -> Option<&DeclSource> {
        let key = decl_key(name);
        self.decls.iter().find(|d| d.kind == kind && d.key == key)
    }

    /// The tokens of a declaration's body (positions in its file).
    fn tokens(&self, d: &DeclSource) -> Result<Vec<Token>, AfError> {
        let text = read_text(&d.file, "declaration file")?;
        let body = text.get(d.body.clone()).unwrap_or("");
        tokenize_from(body, &d.file.display().to_string(), d.body_pos)
    }

    /// The names of every declaration of `kind` (case-insensitive), in scan order.
    pub fn names(&self, kind: &str) -> Vec<&str> {
        self.decls
            .iter()
            .filter(|d| d.kind.eq_ignore_ascii_case(kind))
            .map(|d| d.name.as_str())
            .collect()
    }

    /// A path relative to the base folder, file and folder names matched without
    /// regard to case.
    pub fn path(&self, rel: &str) -> Option<PathBuf> {
        resolve_ci(&self.root, rel)
    }

    fn missing(&self, kind: &str, name: &str) -> AfError {
        let have = self.names(kind);
        let shown: Vec<&str> = have.iter().take(12).copied().collect();
        AfError {
            file: self.root.display().to_string(),
            line: 1,
            col: 1,
            message: format!(
                "no {kind} \"{name}\" in def/ or af/ (there are {}: {}{})",
                have.len(),
                shown.join(", "),
                if have.len() > 12 { ", ..." } else { "" }
            ),
        }
    }

    /// The `entityDef` named `name`, inheritance resolved.
    pub fn entity(&self, name: &str) -> Result<EntityDef, AfError> {
        self.entity_depth(name, 0)
    }

    fn entity_depth(&self, name: &str, depth: u32) -> Result<EntityDef, AfError> {
        let d = self
            .find("entitydef", name)
            .ok_or_else(|| self.missing("entityDef", name))?;
        let fname = d.file.display().to_string();
        if depth > MAX_INHERIT {
            return Err(AfError::at(
                &fname,
                d.body_pos,
                format!("entityDef \"{}\" inherits too deeply (a loop?)", d.name),
            ));
        }
        let tokens = self.tokens(d)?;
        let mut e = EntityDef {
            name: d.name.clone(),
            keys: vec![("classname".into(), d.name.clone())],
        };
        let mut parents = Vec::new();
        let mut it = tokens.iter();
        while let Some(k) = it.next() {
            // idDeclEntityDef::Parse takes only a quoted string as a key (anything else:
            // "Expected quoted string", and the declaration falls back to its default).
            let key = match &k.tok {
                Tok::Str(w) => w.clone(),
                Tok::Eof => break,
                other => {
                    return Err(AfError::at(
                        &fname,
                        k.pos,
                        format!("expected a quoted key, found {}", other.describe()),
                    ));
                }
            };
            let v = it.next().expect("Eof ends the list");
            let value = word(&v.tok).ok_or_else(|| {
                AfError::at(
                    &fname,
                    v.pos,
                    format!("expected a value for \"{key}\", found {}", v.tok.describe()),
                )
            })?;
            if key.to_ascii_lowercase().starts_with("inherit") {
                parents.push((value, v.pos));
            } else {
                e.set(&key, &value);
            }
        }
        for (p, pos) in parents {
            let parent = self.entity_depth(&p, depth + 1).map_err(|err| {
                if err.message.starts_with("no entityDef") {
                    AfError::at(
                        &fname,
                        pos,
                        format!(
                            "entityDef \"{}\" inherits \"{p}\", which does not exist",
                            d.name
                        ),
                    )
                } else {
                    err
                }
            })?;
            for (k, v) in parent.keys {
                if e.get(&k).is_none() {
                    e.keys.push((k, v));
                }
            }
        }
        Ok(e)
    }

    /// The `model` declaration named `name`, inheritance resolved.
    pub fn model(&self, name: &str) -> Result<ModelDecl, AfError> {
        self.model_depth(name, 0)
    }

    fn model_depth(&self, name: &str, depth: u32) -> Result<ModelDecl, AfError> {
        let d = self
            .find("model", name)
            .ok_or_else(|| self.missing("model", name))?;
        let fname = d.file.display().to_string();
        let err = |pos: Pos, m: String| AfError::at(&fname, pos, m);
        if depth > MAX_INHERIT {
            return Err(err(
                d.body_pos,
                format!("model \"{}\" inherits too deeply (a loop?)", d.name),
            ));
        }
        let tokens = self.tokens(d)?;
        let mut m = ModelDecl {
            name: d.name.clone(),
            ..ModelDecl::default()
        };
        let mut i = 0;
        let take = |i: &mut usize, what: &str| -> Result<(String, Pos), AfError> {
            let t = &tokens[(*i).min(tokens.len() - 1)];
            *i += 1;
            word(&t.tok).map(|w| (w, t.pos)).ok_or_else(|| {
                err(
                    t.pos,
                    format!("expected {what}, found {}", t.tok.describe()),
                )
            })
        };
        loop {
            let t = &tokens[i.min(tokens.len() - 1)];
            i += 1;
            // idDeclModelDef::Parse compares the token's text, so a keyword may be
            // quoted ("skin", as env.def writes it).
            let kw = match &t.tok {
                Tok::Eof => break,
                Tok::Ident(s) | Tok::Str(s) => s.as_str(),
                other => {
                    return Err(err(
                        t.pos,
                        format!(
                            "expected a model keyword (inherit, mesh, skin, offset, channel, anim, remove), found {}",
                            other.describe()
                        ),
                    ));
                }
            };
            match kw {
                "inherit" => {
                    let (p, pos) = take(&mut i, "the parent model's name")?;
                    let name = m.name.clone();
                    m = self.model_depth(&p, depth + 1).map_err(|e| {
                        if e.message.starts_with("no model") {
                            err(
                                pos,
                                format!("model \"{name}\" inherits \"{p}\", which does not exist"),
                            )
                        } else {
                            e
                        }
                    })?;
                    m.name = name;
                }
                "mesh" => m.mesh = Some(take(&mut i, "the mesh's path")?.0),
                "skin" => m.skin = Some(take(&mut i, "the skin's name")?.0),
                "offset" => {
                    let mut v = [0f32; 3];
                    expect(&tokens, &mut i, &Tok::LParen, &fname)?;
                    for c in &mut v {
                        let t = &tokens[i.min(tokens.len() - 1)];
                        i += 1;
                        match t.tok {
                            Tok::Num(n) if (n as f32).is_finite() => *c = n as f32,
                            _ => {
                                return Err(err(
                                    t.pos,
                                    format!(
                                        "expected a number in `offset`, found {}",
                                        t.tok.describe()
                                    ),
                                ));
                            }
                        }
                    }
                    expect(&tokens, &mut i, &Tok::RParen, &fname)?;
                    m.offset = Vec3::from_array(v);
                }
                "channel" => {
                    take(&mut i, "the channel's name")?;
                    expect(&tokens, &mut i, &Tok::LParen, &fname)?;
                    skip_to(&tokens, &mut i, &Tok::RParen, t.pos, &fname)?;
                }
                "anim" => {
                    let (name, _) = take(&mut i, "the anim's name")?;
                    let mut files = vec![take(&mut i, "the anim's .md5anim file")?.0];
                    while tokens.get(i).is_some_and(|t| t.tok == Tok::Comma) {
                        i += 1;
                        files.push(take(&mut i, "another .md5anim file after `,`")?.0);
                    }
                    if tokens.get(i).is_some_and(|t| t.tok == Tok::LBrace) {
                        i += 1;
                        skip_to(&tokens, &mut i, &Tok::RBrace, t.pos, &fname)?;
                    }
                    let entry = AnimEntry { name, files };
                    match m.anims.iter_mut().find(|a| a.name == entry.name) {
                        Some(a) => *a = entry,
                        None => m.anims.push(entry),
                    }
                }
                "remove" => {
                    let (name, _) = take(&mut i, "the anim to remove")?;
                    m.anims.retain(|a| a.name != name);
                }
                other => {
                    return Err(err(
                        t.pos,
                        format!(
                            "unknown model keyword `{other}`; expected inherit, mesh, skin, offset, channel, anim or remove"
                        ),
                    ));
                }
            }
        }
        Ok(m)
    }

    /// The `.af` file declaring `articulatedFigure name` and the name as written.
    pub fn figure(&self, name: &str) -> Result<(PathBuf, String), AfError> {
        let d = self
            .find("articulatedfigure", name)
            .ok_or_else(|| self.missing("articulatedFigure", name))?;
        Ok((d.file.clone(), d.name.clone()))
    }

    /// A model key's value as Doom 3 reads it: a model declaration, else a path.
    pub fn model_files(&self, model: &str) -> Result<ModelFiles, AfError> {
        if let Some(d) = self.find("model", model) {
            let m = self.model(model)?;
            // A missing file is reported at the declaration that names it (or inherits
            // it), not at the base folder.
            let here = |e: AfError| AfError {
                file: d.file.display().to_string(),
                line: d.body_pos.line,
                col: d.body_pos.col,
                message: format!("{} {}", e.message, self.root.display()),
            };
            let mesh = match &m.mesh {
                Some(p) => Some(
                    self.file(p, &format!("model \"{}\"'s mesh", m.name))
                        .map_err(here)?,
                ),
                None => None,
            };
            let pose = match m.anim("af_pose") {
                Some(a) => Some(
                    self.file(&a.files[0], &format!("model \"{}\"'s anim af_pose", m.name))
                        .map_err(here)?,
                ),
                None => None,
            };
            Ok(ModelFiles {
                decl: Some(m),
                mesh,
                af_pose: pose,
            })
        } else {
            Ok(ModelFiles {
                decl: None,
                mesh: Some(self.file(model, "the model")?),
                af_pose: None,
            })
        }
    }

    /// A file relative to the base folder that must exist.
    pub fn file(&self, rel: &str, what: &str) -> Result<PathBuf, AfError> {
        self.path(rel).ok_or_else(|| AfError {
            file: self.root.display().to_string(),
            line: 1,
            col: 1,
            message: format!("{what} \"{rel}\" is not in the base folder"),
        })
    }

    /// Resolves entity `name` to its figure, mesh and animations.
    pub fn character(&self, name: &str) -> Result<Doom3Character, AfError> {
        let entity = self.entity(name)?;
        let figure_key = entity.get("ragdoll").or_else(|| entity.get("articulatedFigure")).ok_or_else(|| AfError {
            file: self.find("entitydef", name).map_or(self.root.display().to_string(), |d| d.file.display().to_string()),
            line: 1,
            col: 1,
            message: format!("entityDef \"{}\" names no figure: it has neither `ragdoll` nor `articulatedFigure`", entity.name),
        })?;
        let (af_file, figure) = self.figure(figure_key)?;
        let ModelFiles {
            decl: model,
            mesh,
            af_pose,
        } = match entity.get("model") {
            Some(m) if !m.is_empty() => self.model_files(m)?,
            _ => ModelFiles::default(),
        };
        let mut anims = Vec::new();
        if let Some(m) = &model {
            for a in m.anims.iter().filter(|a| a.name != "af_pose") {
                if let Some(p) = self.path(&a.files[0]) {
                    anims.push((a.name.clone(), p));
                }
            }
        }
        let skin = entity
            .get("skin")
            .map(str::to_string)
            .or_else(|| model.as_ref().and_then(|m| m.skin.clone()));
        Ok(Doom3Character {
            entity,
            model,
            af_file,
            figure,
            mesh,
            af_pose,
            anims,
            skin,
        })
    }
}

/// Most levels of `inherit` followed (a loop would otherwise never end).
const MAX_INHERIT: u32 = 64;

fn io_error(p: &Path, e: std::io::Error) -> AfError {
    AfError {
        file: p.display().to_string(),
        line: 1,
        col: 1,
        message: format!("cannot read the folder: {e}"),
    }
}

/// A token as a word: a bare word, a string, or a number written back.
fn word(t: &Tok) -> Option<String> {
    match t {
        Tok::Ident(s) | Tok::Str(s) => Some(s.clone()),
        Tok::Num(n) => Some(n.to_string()),
        _ => None,
    }
}

fn expect(tokens: &[Token], i: &mut usize, tok: &Tok, file: &str) -> Result<(), AfError> {
    let t = &tokens[(*i).min(tokens.len() - 1)];
    *i += 1;
    if &t.tok == tok {
        Ok(())
    } else {
        Err(AfError::at(
            file,
            t.pos,
            format!("expected {}, found {}", tok.describe(), t.tok.describe()),
        ))
    }
}

/// Skips past the next `close` (not nested); `from` is where the group opened.
fn skip_to(
    tokens: &[Token],
    i: &mut usize,
    close: &Tok,
    from: Pos,
    file: &str,
) -> Result<(), AfError> {
    loop {
        let t = &tokens[(*i).min(tokens.len() - 1)];
        *i += 1;
        if &t.tok == close {
            return Ok(());
        }
        if t.tok == Tok::Eof {
            return Err(AfError::at(
                file,
                from,
                format!("this is never closed with {}", close.describe()),
            ));
        }
    }
}

/// `rel` under `root`, each component matched without regard to case when the exact
/// name is not there.
pub fn resolve_ci(root: &Path, rel: &str) -> Option<PathBuf> {
    let mut p = root.to_path_buf();
    for part in rel
        .split(['/', '\\'])
        .filter(|s| !s.is_empty() && *s != ".")
    {
        let exact = p.join(part);
        if exact.exists() {
            p = exact;
            continue;
        }
        let found = std::fs::read_dir(&p)
            .ok()?
            .filter_map(|e| e.ok())
            .find(|e| e.file_name().to_string_lossy().eq_ignore_ascii_case(part))?;
        p = found.path();
    }
    p.exists().then_some(p)
}

/// A character scanner for finding declaration boundaries.
struct Scanner {
    chars: Vec<char>,
    /// Byte offset of each char, plus the text's length at the end.
    offsets: Vec<usize>,
    k: usize,
    /// Byte offset of `chars[k]`.
    i: usize,
    line: u32,
    col: u32,
}

impl Scanner {
    fn new(text: &str) -> Scanner {
        let mut offsets: Vec<usize> = text.char_indices().map(|(o, _)| o).collect();
        offsets.push(text.len());
        let chars: Vec<char> = text.chars().collect();
        let k = usize::from(chars.first() == Some(&'\u{feff}'));
        Scanner {
            i: offsets[k],
            chars,
            offsets,
            k,
            line: 1,
            col: 1,
        }
    }
    fn pos(&self) -> Pos {
        Pos {
            line: self.line,
            col: self.col,
        }
    }
    fn peek(&self) -> Option<char> {
        self.chars.get(self.k).copied()
    }
    fn peek2(&self) -> Option<char> {
        self.chars.get(self.k + 1).copied()
    }
    fn bump(&mut self) {
        if self.peek() == Some('\n') {
            self.line += 1;
            self.col = 1;
        } else {
            self.col += 1;
        }
        self.k += 1;
        self.i = self.offsets[self.k.min(self.offsets.len() - 1)];
    }
    /// Skips whitespace and comments.
    fn skip_space(&mut self, file: &str) -> Result<(), AfError> {
        loop {
            match (self.peek(), self.peek2()) {
                (Some(c), _) if c.is_whitespace() => self.bump(),
                (Some('/'), Some('/')) => {
                    while self.peek().is_some_and(|c| c != '\n') {
                        self.bump();
                    }
                }
                (Some('/'), Some('*')) => {
                    let at = self.pos();
                    self.bump();
                    self.bump();
                    while !(self.peek() == Some('*') && self.peek2() == Some('/')) {
                        if self.peek().is_none() {
                            return Err(AfError::at(
                                file,
                                at,
                                "this `/*` comment is never closed with `*/`".into(),
                            ));
                        }
                        self.bump();
                    }
                    self.bump();
                    self.bump();
                }
                _ => return Ok(()),
            }
        }
    }
    /// A quoted string or a bare word (up to whitespace, a brace or a comment).
    fn word(&mut self, file: &str) -> Result<String, AfError> {
        let mut w = String::new();
        if self.peek() == Some('"') {
            let at = self.pos();
            self.bump();
            loop {
                match self.peek() {
                    None | Some('\n') => {
                        return Err(AfError::at(
                            file,
                            at,
                            "this string is never closed with `\"`".into(),
                        ));
                    }
                    Some('"') => {
                        self.bump();
                        return Ok(w);
                    }
                    Some(c) => {
                        w.push(c);
                        self.bump();
                    }
                }
            }
        }
        while let Some(c) = self.peek() {
            let comment = c == '/' && matches!(self.peek2(), Some('/' | '*'));
            if c.is_whitespace() || c == '{' || c == '}' || c == '"' || comment {
                break;
            }
            w.push(c);
            self.bump();
        }
        Ok(w)
    }
    /// Skips to just past the `}` that closes the `{` at `open` (already consumed),
    /// over nested braces, strings and comments.
    fn skip_block(&mut self, file: &str, open: Pos) -> Result<(), AfError> {
        let mut depth = 1u32;
        loop {
            self.skip_space(file)?;
            match self.peek() {
                None => {
                    return Err(AfError::at(
                        file,
                        open,
                        "this `{` is never closed with `}`".into(),
                    ));
                }
                Some('{') => {
                    depth += 1;
                    self.bump();
                }
                Some('}') => {
                    self.bump();
                    depth -= 1;
                    if depth == 0 {
                        return Ok(());
                    }
                }
                Some('"') => {
                    self.word(file)?;
                }
                Some(_) => {
                    let before = self.k;
                    self.word(file)?;
                    if self.k == before {
                        self.bump();
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn declaration_keys_fold_case_slashes_and_extension() {
        assert_eq!(decl_key("Monster_Zombie.af"), "monster_zombie");
        assert_eq!(decl_key("a\\B"), "a/b");
        assert_eq!(decl_key("x.y/z"), "x.y/z");
    }

    #[test]
    fn scanning_finds_declarations_and_their_bodies() {
        let mut b = Doom3Base {
            root: PathBuf::new(),
            decls: Vec::new(),
            warnings: Vec::new(),
        };
        let text = "/* header { } */\nentityDef Foo { \"model\" \"m\" // }\n}\nbar { \"a\" \"{\" }\nmodel m { mesh x/y.md5mesh anim walk w.md5anim { frame 1 call x } }\n";
        b.scan(Path::new("t.def"), text, "entitydef").unwrap();
        let names: Vec<_> = b
            .decls
            .iter()
            .map(|d| (d.kind.as_str(), d.name.as_str()))
            .collect();
        assert_eq!(
            names,
            [("entitydef", "Foo"), ("entitydef", "bar"), ("model", "m")]
        );
        assert_eq!(b.decls[0].body_pos, Pos { line: 2, col: 16 });
        assert_eq!(&text[b.decls[1].body.clone()], " \"a\" \"{\" ");
        let e = b
            .scan(
                Path::new("u.def"),
                "entityDef x {\n \"a\" \"b\"\n",
                "entitydef",
            )
            .unwrap_err();
        assert_eq!((e.line, e.col), (1, 13));
    }
}
