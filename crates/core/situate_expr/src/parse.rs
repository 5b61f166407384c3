//! The parser: tokens read by precedence into the program, in one pass with
//! the type checker (`check.rs`), which builds and types each part as soon
//! as it is read. This file steers: precedence, brackets, calls and the
//! limits on size and nesting.

use crate::lex::{column_of, lex, lex_err, Tok, Token};
use crate::program::{Node, Program, Ty};
use crate::{ExprError, Resolver, MAX_DEPTH, MAX_NODES, MAX_SOURCE_BYTES};

/// Parses and type-checks `source` (a condition or a formula), resolving its
/// names with `resolver`; `want` refuses the whole expression's type with a
/// message (None: accepted).
pub(crate) fn compile_program(
    source: &str,
    resolver: &dyn Resolver,
    noun: &'static str,
    want: impl Fn(Ty) -> Option<String>,
) -> Result<(Program, Vec<String>, Ty), ExprError> {
    if source.len() > MAX_SOURCE_BYTES {
        return Err(ExprError {
            column: 1,
            message: format!("the {noun} is too long: {} bytes, at most {MAX_SOURCE_BYTES}", source.len()),
        });
    }
    let toks = lex(source)?;
    let mut p = Parser {
        src: source,
        toks,
        pos: 0,
        depth: 0,
        resolver,
        program: Program::default(),
        ref_names: Vec::new(),
        fixed: Vec::new(),
        noun,
    };
    if p.peek().tok == Tok::End {
        return Err(p.err(0, format!("the {noun} is empty")));
    }
    let e = p.parse_expr()?;
    if p.peek().tok != Tok::End {
        return Err(p.unexpected(&format!("an operator or the end of the {noun}")));
    }
    if let Some(message) = want(e.ty) {
        return Err(p.err(e.at, message));
    }
    p.program.root = e.node;
    Ok((p.program, p.ref_names, e.ty))
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum BinOp {
    Or,
    And,
    Eq,
    Ne,
    Lt,
    Le,
    Gt,
    Ge,
    Add,
    Sub,
    Mul,
    Div,
    Rem,
}

impl BinOp {
    fn from_tok(t: &Tok) -> Option<BinOp> {
        Some(match t {
            Tok::OrOr => BinOp::Or,
            Tok::AndAnd => BinOp::And,
            Tok::EqEq => BinOp::Eq,
            Tok::NotEq => BinOp::Ne,
            Tok::Lt => BinOp::Lt,
            Tok::Le => BinOp::Le,
            Tok::Gt => BinOp::Gt,
            Tok::Ge => BinOp::Ge,
            Tok::Plus => BinOp::Add,
            Tok::Minus => BinOp::Sub,
            Tok::Star => BinOp::Mul,
            Tok::Slash => BinOp::Div,
            Tok::Percent => BinOp::Rem,
            _ => return None,
        })
    }

    fn prec(self) -> u8 {
        match self {
            BinOp::Or => 1,
            BinOp::And => 2,
            BinOp::Eq | BinOp::Ne => 3,
            BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge => 4,
            BinOp::Add | BinOp::Sub => 5,
            BinOp::Mul | BinOp::Div | BinOp::Rem => 6,
        }
    }

    fn chains(self) -> bool {
        self.prec() != 3 && self.prec() != 4
    }

    pub(crate) fn text(self) -> &'static str {
        match self {
            BinOp::Or => "||",
            BinOp::And => "&&",
            BinOp::Eq => "==",
            BinOp::Ne => "!=",
            BinOp::Lt => "<",
            BinOp::Le => "<=",
            BinOp::Gt => ">",
            BinOp::Ge => ">=",
            BinOp::Add => "+",
            BinOp::Sub => "-",
            BinOp::Mul => "*",
            BinOp::Div => "/",
            BinOp::Rem => "%",
        }
    }
}

/// A compiled, typed subexpression; `at` is the byte offset where it starts.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Typed {
    pub(crate) node: u32,
    pub(crate) ty: Ty,
    pub(crate) at: usize,
}

pub(crate) struct Parser<'s, 'r> {
    src: &'s str,
    toks: Vec<Token>,
    pos: usize,
    depth: usize,
    pub(crate) resolver: &'r dyn Resolver,
    pub(crate) program: Program,
    pub(crate) ref_names: Vec<String>,
    /// Name nodes of fixed-length arrays: their name and length, so that a
    /// constant index beyond the end is refused where it is written.
    pub(crate) fixed: Vec<(u32, String, usize)>,
    /// What is parsed, for messages: "condition" or "formula".
    noun: &'static str,
}

pub(crate) type PResult<T> = Result<T, ExprError>;

impl Parser<'_, '_> {
    // The functions on the recursion path (`parse_expr`, `parse_operand`,
    // `parse_primary`, `call`) only steer; everything else, in particular
    // formatting error messages, happens in helpers kept out of line, so the
    // recursive frames stay small even in debug builds.

    pub(crate) fn err(&self, at: usize, message: impl Into<String>) -> ExprError {
        lex_err(self.src, at, message)
    }

    pub(crate) fn peek(&self) -> &Token {
        // The token list always ends with `End`, and `pos` never passes it.
        &self.toks[self.pos.min(self.toks.len() - 1)]
    }

    pub(crate) fn bump(&mut self) {
        if self.peek().tok != Tok::End {
            self.pos += 1;
        }
    }

    fn describe(&self, t: &Token) -> String {
        if t.tok == Tok::End {
            return format!("the end of the {}", self.noun);
        }
        let text = self.src.get(t.start..t.end).unwrap_or("?");
        if text.chars().count() > 24 {
            let short: String = text.chars().take(20).collect();
            format!("`{short}…`")
        } else {
            format!("`{text}`")
        }
    }

    /// "expected {what}, found …" at the next token.
    #[cold]
    #[inline(never)]
    pub(crate) fn unexpected(&self, what: &str) -> ExprError {
        let t = self.peek();
        self.err(t.start, format!("expected {what}, found {}", self.describe(t)))
    }

    #[inline(never)]
    pub(crate) fn push(&mut self, node: Node, at: usize) -> PResult<u32> {
        if self.program.nodes.len() >= MAX_NODES {
            return Err(self.err(
                at,
                format!("the {} is too large: more than {MAX_NODES} parts (names, literals, operators)", self.noun),
            ));
        }
        self.program.nodes.push(node);
        Ok((self.program.nodes.len() - 1) as u32)
    }

    #[inline(never)]
    fn enter(&mut self, at: usize) -> PResult<()> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(self.err(at, format!("the {} nests too deeply (more than {MAX_DEPTH} levels)", self.noun)));
        }
        Ok(())
    }

    fn leave(&mut self) {
        self.depth = self.depth.saturating_sub(1);
    }

    /// Expects the `)` or `]` that closes the bracket opened at `open`.
    #[inline(never)]
    fn expect_close(&mut self, open: usize) -> PResult<()> {
        let (close, text, opener) = if self.src.as_bytes().get(open) == Some(&b'[') {
            (Tok::RBracket, "]", "[")
        } else {
            (Tok::RParen, ")", "(")
        };
        if self.peek().tok == close {
            self.bump();
            return Ok(());
        }
        let what = format!("`{text}` to close the `{opener}` at column {}", column_of(self.src, open));
        Err(self.unexpected(&what))
    }

    /// An expression: operands joined by binary operators, parsed with an
    /// operator stack (shunting yard); equal precedences reduce left to
    /// right, and comparisons refuse to chain.
    fn parse_expr(&mut self) -> PResult<Typed> {
        let mut operands: Vec<Typed> = Vec::new();
        let mut ops: Vec<(BinOp, usize)> = Vec::new();
        operands.push(self.parse_operand()?);
        while let Some(op) = BinOp::from_tok(&self.peek().tok) {
            let at = self.peek().start;
            while let Some(&(top, top_at)) = ops.last() {
                if top.prec() < op.prec() {
                    break;
                }
                if top.prec() == op.prec() && !op.chains() {
                    return Err(self.chain_error(top, op, at));
                }
                ops.pop();
                self.reduce(&mut operands, top, top_at)?;
            }
            ops.push((op, at));
            self.bump();
            operands.push(self.parse_operand()?);
        }
        while let Some((op, at)) = ops.pop() {
            self.reduce(&mut operands, op, at)?;
        }
        match (operands.pop(), operands.is_empty()) {
            (Some(e), true) => Ok(e),
            _ => Err(self.err(0, "internal error: unbalanced expression")),
        }
    }

    #[cold]
    #[inline(never)]
    fn chain_error(&self, prev: BinOp, op: BinOp, at: usize) -> ExprError {
        self.err(
            at,
            format!(
                "comparisons don't chain: `{}` cannot follow `{}`; combine two comparisons with `&&` (`a < b && b < c`) or add parentheses",
                op.text(),
                prev.text()
            ),
        )
    }

    #[inline(never)]
    fn reduce(&mut self, operands: &mut Vec<Typed>, op: BinOp, at: usize) -> PResult<()> {
        let (Some(r), Some(l)) = (operands.pop(), operands.pop()) else {
            return Err(self.err(at, "internal error: missing operand"));
        };
        let e = self.binary(op, at, l, r)?;
        operands.push(e);
        Ok(())
    }

    /// Prefix operators, a primary, then indexes: `-x[0]` is `-(x[0])`.
    fn parse_operand(&mut self) -> PResult<Typed> {
        // (is `!`, offset) of each prefix operator, innermost last.
        let mut prefix: Vec<(bool, usize)> = Vec::new();
        loop {
            let not = match self.peek().tok {
                Tok::Bang => true,
                Tok::Minus => false,
                _ => break,
            };
            let at = self.peek().start;
            self.enter(at)?;
            self.bump();
            prefix.push((not, at));
        }
        let mut e = self.parse_primary()?;
        while self.peek().tok == Tok::LBracket {
            let open = self.peek().start;
            self.check_indexable(e, open)?;
            self.bump();
            self.enter(open)?;
            let idx = self.parse_expr()?;
            self.expect_close(open)?;
            self.leave();
            e = self.index(e, idx, open)?;
        }
        while let Some((not, at)) = prefix.pop() {
            self.leave();
            e = self.unary(not, at, e)?;
        }
        Ok(e)
    }

    fn parse_primary(&mut self) -> PResult<Typed> {
        let at = self.peek().start;
        match &self.peek().tok {
            Tok::LParen => {
                self.bump();
                self.enter(at)?;
                let e = self.parse_expr()?;
                self.expect_close(at)?;
                self.leave();
                Ok(Typed { at, ..e })
            }
            Tok::Name(name) => {
                let name = name.clone();
                self.bump();
                if self.peek().tok == Tok::LParen {
                    self.call(name, at)
                } else {
                    self.reference(&name, at)
                }
            }
            _ => self.literal(),
        }
    }

    /// A call of the function `name` at `at`; the next token is its `(`.
    fn call(&mut self, name: String, at: usize) -> PResult<Typed> {
        self.check_function(&name, at)?;
        let open = self.peek().start;
        self.bump();
        self.enter(open)?;
        let mut args: Vec<Typed> = Vec::new();
        if self.peek().tok == Tok::RParen {
            self.bump();
        } else {
            loop {
                args.push(self.parse_expr()?);
                match self.peek().tok {
                    Tok::Comma => self.bump(),
                    Tok::RParen => {
                        self.bump();
                        break;
                    }
                    _ => return Err(self.unexpected(&format!("`,` or `)` in the call to `{name}`"))),
                }
            }
        }
        self.leave();
        self.build_call(&name, at, &args)
    }
}
