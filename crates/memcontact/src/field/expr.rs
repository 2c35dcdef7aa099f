//! Compiled scalar expressions of the position `(x, y)`: the formulas that describe the
//! problem data f, φ and h (docs/theory.md#physics) when they are not constants.
//!
//! An [`Expr`] is parsed once, constant-folded, and compiled into a flat stack-machine
//! program; [`Expr::eval`] then runs that program without allocating (for expressions of
//! ordinary size), so it can be called at every quadrature point from many threads.
//!
//! # Grammar
//!
//! From the loosest to the tightest binding:
//!
//! | level | operators | notes |
//! | --- | --- | --- |
//! | or | `a \|\| b` | 1 if a or b is non-zero, else 0; b is evaluated only when a is zero |
//! | and | `a && b` | 1 if a and b are non-zero, else 0; b is evaluated only when a is non-zero |
//! | equality | `a == b`, `a != b` | 1 or 0; not chainable |
//! | comparison | `a < b`, `<=`, `>`, `>=` | 1 or 0; not chainable (`0 < x < 1` is an error) |
//! | sum | `a + b`, `a - b` | left-associative |
//! | product | `a * b`, `a / b` | left-associative |
//! | unary | `-a`, `+a`, `!a` | `!a` is 1 when a is 0, else 0 |
//! | power | `a ^ b` (also `a ** b`) | right-associative, tighter than unary minus: `-2^2 = -4`, `2^-1 = 0.5` |
//!
//! Operands are numbers (`1`, `2.5`, `1e-3`, `.5`), the variables `x`, `y` and
//! `r = sqrt(x² + y²)`, the constants `pi` and `e`, parentheses, and function calls:
//! `sin cos tan asin acos atan sinh cosh tanh exp ln log log10 sqrt abs floor ceil round
//! sign step` (one argument; `log` is the natural logarithm, `round` rounds half away from
//! zero, `sign(0) = 0`, `step(s)` is 1 for `s ≥ 0` and 0 otherwise), `atan2(y, x)`,
//! `pow(a, b)`, `hypot(a, b)` (two arguments), `min(a, ...)`, `max(a, ...)` (one or more),
//! and `if(c, a, b)`: a where c ≠ 0, else b. Only the branch taken is evaluated, so a NaN in
//! the other branch never leaks.
//!
//! # NaN
//!
//! NaN is never silently turned into a number: comparisons, logical operators, `min`,
//! `max`, `sign`, `step` and the condition of `if` all return NaN when an operand they
//! look at is NaN, so that the data checks of [`crate::field`] catch it.

use crate::error::excerpt;
use crate::error::{Error, Result};
use std::fmt;

/// Nesting limit of parentheses, unary operators and exponents (protects the parser's stack).
const MAX_NESTING: usize = 128;
/// Limit on the depth of the expression tree (protects the compiler's stack).
const MAX_TREE_DEPTH: u32 = 1000;
/// Programs needing at most this many stack slots evaluate without allocating.
const INLINE_STACK: usize = 24;
/// Points evaluated together by [`Expr::eval_many`].
const LANES: usize = 8;
/// The deepest stack [`Expr::eval_many`] runs on many points at once (deeper programs run
/// point by point): 1 KB to clear per call instead of the 1.5 KB of [`INLINE_STACK`].
const LANE_STACK: usize = 16;

/// A compiled scalar expression of `x` and `y`.
///
/// Parse with [`Expr::parse`] (or `str::parse`), evaluate with [`Expr::eval`]. The grammar
/// is that of the case file (docs/case-file/index.md#expressions).
///
/// ```
/// use memcontact::field::Expr;
/// let e = Expr::parse("0.5 + 0.1*sin(2*pi*x)*cos(2*pi*y)").unwrap();
/// assert!((e.eval(0.25, 0.0) - 0.6).abs() < 1e-15);
/// assert_eq!(Expr::parse("2^10 - 24").unwrap().constant_value(), Some(1000.0));
/// ```
#[derive(Clone)]
pub struct Expr {
    source: String,
    program: Box<[Op]>,
    stack: usize,
    constant: Option<f64>,
    /// The program has no `if`: [`Expr::eval_many`] may run it on many points at once.
    straight: bool,
}

impl Expr {
    /// Parses and compiles `src`.
    ///
    /// Errors ([`Error::Expr`]) name the problem and its column (counted in characters from
    /// 1): unknown variables and functions, wrong numbers of arguments, unbalanced
    /// parentheses, missing operands or operators, an empty expression.
    pub fn parse(src: &str) -> Result<Expr> {
        let fail = |message: String| Error::Expr {
            expr: src.to_string(),
            message,
        };
        let tokens = lex(src).map_err(fail)?;
        let tree = Parser {
            tokens,
            pos: 0,
            nesting: 0,
        }
        .parse_all()
        .map_err(fail)?;
        let tree = fold(tree.node);
        let constant = match tree {
            Node::Num(v) => Some(v),
            _ => None,
        };
        let mut program = Vec::new();
        compile(&tree, &mut program);
        let stack = stack_bound(&program);
        let straight = !program
            .iter()
            .any(|op| matches!(op, Op::Branch { .. } | Op::Jump(_)));
        Ok(Expr {
            source: src.to_string(),
            program: program.into_boxed_slice(),
            stack,
            constant,
            straight,
        })
    }

    /// The value at the point `(x, y)`.
    #[inline]
    pub fn eval(&self, x: f64, y: f64) -> f64 {
        if let Some(c) = self.constant {
            return c;
        }
        if self.stack <= INLINE_STACK {
            let mut stack = [0.0; INLINE_STACK];
            run(&self.program, x, y, &mut stack)
        } else {
            let mut stack = vec![0.0; self.stack];
            run(&self.program, x, y, &mut stack)
        }
    }

    /// The values at the points `points` into `out` (of the same length), bitwise those of
    /// [`Expr::eval`] at each. Without `if` the program runs once per eight points, every
    /// instruction on all of them: the interpreter's dispatch is paid once per batch, not
    /// once per point (assembly and the error estimator evaluate f at seven quadrature
    /// points of every triangle).
    pub fn eval_many(&self, points: &[[f64; 2]], out: &mut [f64]) {
        assert_eq!(points.len(), out.len(), "one value per point");
        if let Some(c) = self.constant {
            out.fill(c);
            return;
        }
        if !self.straight || self.stack > LANE_STACK {
            for (o, p) in out.iter_mut().zip(points) {
                *o = self.eval(p[0], p[1]);
            }
            return;
        }
        let mut stack = [[0.0; LANES]; LANE_STACK];
        for (pc, oc) in points.chunks(LANES).zip(out.chunks_mut(LANES)) {
            let (mut x, mut y) = ([0.0; LANES], [0.0; LANES]);
            for (l, p) in pc.iter().enumerate() {
                (x[l], y[l]) = (p[0], p[1]);
            }
            run_lanes(&self.program, &x, &y, &mut stack);
            oc.copy_from_slice(&stack[0][..oc.len()]);
        }
    }

    /// The text the expression was parsed from.
    pub fn source(&self) -> &str {
        &self.source
    }

    /// The value when the expression does not depend on the position (after constant
    /// folding: `2*pi`, `if(1, 3, x)` are constant; `x - x` is not recognised as such).
    pub fn constant_value(&self) -> Option<f64> {
        self.constant
    }
}

impl fmt::Debug for Expr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Expr")
            .field("source", &self.source)
            .field("constant", &self.constant)
            .field("ops", &self.program.len())
            .finish()
    }
}

impl fmt::Display for Expr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.source)
    }
}

/// Two expressions are equal when their source texts are.
impl PartialEq for Expr {
    fn eq(&self, other: &Self) -> bool {
        self.source == other.source
    }
}

impl std::str::FromStr for Expr {
    type Err = Error;
    fn from_str(s: &str) -> Result<Expr> {
        Expr::parse(s)
    }
}

// ---------------------------------------------------------------------------------------
// Operations: the single definition of what every operator and function computes, shared
// by constant folding and by the evaluator.

/// Functions of one value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum UnOp {
    Neg,
    Not,
    /// 1 if non-zero, else 0 (NaN stays NaN): the right operand of `&&` and `||`.
    Truthy,
    Square,
    Sin,
    Cos,
    Tan,
    Asin,
    Acos,
    Atan,
    Sinh,
    Cosh,
    Tanh,
    Exp,
    Ln,
    Log10,
    Sqrt,
    Abs,
    Floor,
    Ceil,
    Round,
    Sign,
    Step,
}

#[inline]
fn bool_value(b: bool) -> f64 {
    if b {
        1.0
    } else {
        0.0
    }
}

impl UnOp {
    #[inline]
    fn apply(self, a: f64) -> f64 {
        match self {
            UnOp::Neg => -a,
            UnOp::Not if a.is_nan() => a,
            UnOp::Not => bool_value(a == 0.0),
            UnOp::Truthy if a.is_nan() => a,
            UnOp::Truthy => bool_value(a != 0.0),
            UnOp::Square => a * a,
            UnOp::Sin => a.sin(),
            UnOp::Cos => a.cos(),
            UnOp::Tan => a.tan(),
            UnOp::Asin => a.asin(),
            UnOp::Acos => a.acos(),
            UnOp::Atan => a.atan(),
            UnOp::Sinh => a.sinh(),
            UnOp::Cosh => a.cosh(),
            UnOp::Tanh => a.tanh(),
            UnOp::Exp => a.exp(),
            UnOp::Ln => a.ln(),
            UnOp::Log10 => a.log10(),
            UnOp::Sqrt => a.sqrt(),
            UnOp::Abs => a.abs(),
            UnOp::Floor => a.floor(),
            UnOp::Ceil => a.ceil(),
            UnOp::Round => a.round(),
            UnOp::Sign if a == 0.0 || a.is_nan() => a,
            UnOp::Sign => a.signum(),
            UnOp::Step if a.is_nan() => a,
            UnOp::Step => bool_value(a >= 0.0),
        }
    }
}

impl UnOp {
    /// [`UnOp::apply`] on every lane, with the choice of function made once.
    #[inline]
    fn apply_lanes(self, a: &mut [f64; LANES]) {
        macro_rules! each {
            ($($f:ident),*) => {
                match self {
                    $(UnOp::$f => a.iter_mut().for_each(|v| *v = UnOp::$f.apply(*v)),)*
                }
            };
        }
        each!(
            Neg, Not, Truthy, Square, Sin, Cos, Tan, Asin, Acos, Atan, Sinh, Cosh, Tanh, Exp, Ln,
            Log10, Sqrt, Abs, Floor, Ceil, Round, Sign, Step
        )
    }
}

/// Functions of two values.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum BinOp {
    Add,
    Sub,
    Mul,
    Div,
    Pow,
    Lt,
    Le,
    Gt,
    Ge,
    Eq,
    Ne,
    Atan2,
    Hypot,
    Min,
    Max,
}

impl BinOp {
    #[inline]
    fn apply(self, a: f64, b: f64) -> f64 {
        match self {
            BinOp::Add => a + b,
            BinOp::Sub => a - b,
            BinOp::Mul => a * b,
            BinOp::Div => a / b,
            BinOp::Pow => a.powf(b),
            BinOp::Atan2 => a.atan2(b),
            BinOp::Hypot => a.hypot(b),
            _ if a.is_nan() || b.is_nan() => f64::NAN,
            BinOp::Lt => bool_value(a < b),
            BinOp::Le => bool_value(a <= b),
            BinOp::Gt => bool_value(a > b),
            BinOp::Ge => bool_value(a >= b),
            BinOp::Eq => bool_value(a == b),
            BinOp::Ne => bool_value(a != b),
            BinOp::Min => a.min(b),
            BinOp::Max => a.max(b),
        }
    }
}

/// Where the operands of a [`BinOp`] on lanes come from.
#[derive(Clone, Copy)]
enum Operands<'a> {
    /// `a ∘ b` lane by lane, into a.
    Lanes(&'a [f64; LANES]),
    /// `a ∘ c`.
    Right(f64),
    /// `c ∘ a`.
    Left(f64),
}

impl BinOp {
    /// [`BinOp::apply`] on every lane of `a` with the other operand from `with`, the
    /// choice of function made once.
    #[inline]
    fn apply_lanes(self, a: &mut [f64; LANES], with: Operands) {
        macro_rules! each {
            ($($f:ident),*) => {
                match self {
                    $(BinOp::$f => match with {
                        Operands::Lanes(b) => a
                            .iter_mut()
                            .zip(b)
                            .for_each(|(v, &w)| *v = BinOp::$f.apply(*v, w)),
                        Operands::Right(c) => a.iter_mut().for_each(|v| *v = BinOp::$f.apply(*v, c)),
                        Operands::Left(c) => a.iter_mut().for_each(|v| *v = BinOp::$f.apply(c, *v)),
                    },)*
                }
            };
        }
        each!(Add, Sub, Mul, Div, Pow, Lt, Le, Gt, Ge, Eq, Ne, Atan2, Hypot, Min, Max)
    }
}

/// One instruction of the stack machine.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Op {
    Const(f64),
    X,
    Y,
    R,
    Un(UnOp),
    /// Pops b, a; pushes a ∘ b.
    Bin(BinOp),
    /// Replaces the top a by a ∘ c.
    BinC(BinOp, f64),
    /// Replaces the top b by c ∘ b.
    CBin(BinOp, f64),
    /// Pops the condition of an `if`: non-zero continues with the next instruction, zero
    /// jumps to `else_at`, NaN pushes NaN and jumps to `end_at`.
    Branch {
        else_at: u32,
        end_at: u32,
    },
    /// Continues at the given instruction.
    Jump(u32),
}

/// The variable `r`: the distance from the origin.
#[inline(always)]
fn radius(x: f64, y: f64) -> f64 {
    (x * x + y * y).sqrt()
}

/// Runs `program`; `stack` has at least [`stack_bound`] slots.
#[inline]
fn run(program: &[Op], x: f64, y: f64, stack: &mut [f64]) -> f64 {
    // `sp` is the number of values on the stack; the top is `stack[sp - 1]`.
    let mut sp = 0usize;
    let mut pc = 0usize;
    while let Some(op) = program.get(pc) {
        pc += 1;
        match *op {
            Op::Const(c) => {
                stack[sp] = c;
                sp += 1;
            }
            Op::X => {
                stack[sp] = x;
                sp += 1;
            }
            Op::Y => {
                stack[sp] = y;
                sp += 1;
            }
            Op::R => {
                stack[sp] = radius(x, y);
                sp += 1;
            }
            Op::Un(f) => stack[sp - 1] = f.apply(stack[sp - 1]),
            Op::Bin(f) => {
                sp -= 1;
                stack[sp - 1] = f.apply(stack[sp - 1], stack[sp]);
            }
            Op::BinC(f, c) => stack[sp - 1] = f.apply(stack[sp - 1], c),
            Op::CBin(f, c) => stack[sp - 1] = f.apply(c, stack[sp - 1]),
            Op::Branch { else_at, end_at } => {
                sp -= 1;
                let c = stack[sp];
                if c.is_nan() {
                    stack[sp] = c;
                    sp += 1;
                    pc = end_at as usize;
                } else if c == 0.0 {
                    pc = else_at as usize;
                }
            }
            Op::Jump(to) => pc = to as usize,
        }
    }
    stack[0]
}

/// Runs a `program` without branches on [`LANES`] points at once (each lane computes
/// exactly what [`run`] computes at its point); the values end in `stack[0]`.
#[inline]
fn run_lanes(
    program: &[Op],
    x: &[f64; LANES],
    y: &[f64; LANES],
    stack: &mut [[f64; LANES]; LANE_STACK],
) {
    let mut sp = 0usize;
    for op in program {
        match *op {
            Op::Const(c) => {
                stack[sp] = [c; LANES];
                sp += 1;
            }
            Op::X => {
                stack[sp] = *x;
                sp += 1;
            }
            Op::Y => {
                stack[sp] = *y;
                sp += 1;
            }
            Op::R => {
                stack[sp] = std::array::from_fn(|l| radius(x[l], y[l]));
                sp += 1;
            }
            Op::Un(f) => f.apply_lanes(&mut stack[sp - 1]),
            Op::Bin(f) => {
                sp -= 1;
                let (below, top) = stack.split_at_mut(sp);
                f.apply_lanes(&mut below[sp - 1], Operands::Lanes(&top[0]));
            }
            Op::BinC(f, c) => f.apply_lanes(&mut stack[sp - 1], Operands::Right(c)),
            Op::CBin(f, c) => f.apply_lanes(&mut stack[sp - 1], Operands::Left(c)),
            Op::Branch { .. } | Op::Jump(_) => {
                unreachable!("programs with branches run point by point")
            }
        }
    }
}

/// An upper bound of the stack depth `program` reaches, from a straight-line walk (which
/// counts both branches of an `if`, so it can only overestimate).
fn stack_bound(program: &[Op]) -> usize {
    let (mut depth, mut max) = (0usize, 1usize);
    for op in program {
        match op {
            Op::Const(_) | Op::X | Op::Y | Op::R => depth += 1,
            Op::Bin(_) | Op::Branch { .. } => depth = depth.saturating_sub(1),
            Op::Un(_) | Op::BinC(..) | Op::CBin(..) | Op::Jump(_) => {}
        }
        max = max.max(depth);
    }
    // The NaN path of a branch pushes one value where the branches would.
    max + 1
}

// ---------------------------------------------------------------------------------------
// Syntax tree, folding and compilation.

#[derive(Debug)]
enum Node {
    Num(f64),
    X,
    Y,
    R,
    Un(UnOp, Box<Node>),
    Bin(BinOp, Box<Node>, Box<Node>),
    If(Box<Node>, Box<Node>, Box<Node>),
    /// `a op₁ b op₂ c …` evaluated from left to right (a flat sum, product or `min`/`max`
    /// of many terms): the same operations in the same order as the nested
    /// left-associative tree, without its depth.
    Chain(Box<Node>, Vec<(BinOp, Node)>),
}

/// Constant folding: every operation whose operands are all numbers is computed now, and
/// an `if` with a constant condition is replaced by its branch.
fn fold(node: Node) -> Node {
    match node {
        Node::Un(f, a) => match fold(*a) {
            Node::Num(v) => Node::Num(f.apply(v)),
            a => Node::Un(f, Box::new(a)),
        },
        Node::Bin(f, a, b) => match (fold(*a), fold(*b)) {
            (Node::Num(u), Node::Num(v)) => Node::Num(f.apply(u, v)),
            // a² as a product: exact (the correctly rounded a·a), and much faster than powf.
            (a, Node::Num(v)) if f == BinOp::Pow && v == 2.0 => Node::Un(UnOp::Square, Box::new(a)),
            (a, b) => Node::Bin(f, Box::new(a), Box::new(b)),
        },
        Node::If(c, a, b) => match fold(*c) {
            Node::Num(v) if v.is_nan() => Node::Num(v),
            Node::Num(v) if v != 0.0 => fold(*a),
            Node::Num(_) => fold(*b),
            c => Node::If(Box::new(c), Box::new(fold(*a)), Box::new(fold(*b))),
        },
        Node::Chain(first, rest) => {
            // Constants fold while everything before them is constant: later ones stay
            // in place (floating-point operations do not reassociate).
            let mut acc = fold(*first);
            let mut kept: Vec<(BinOp, Node)> = Vec::new();
            for (f, b) in rest {
                match (&acc, fold(b), kept.is_empty()) {
                    (Node::Num(u), Node::Num(v), true) => acc = Node::Num(f.apply(*u, v)),
                    (_, b, _) => kept.push((f, b)),
                }
            }
            match kept.len() {
                0 => acc,
                1 => {
                    let (f, b) = kept.pop().expect("one term");
                    fold(Node::Bin(f, Box::new(acc), Box::new(b)))
                }
                _ => Node::Chain(Box::new(acc), kept),
            }
        }
        leaf => leaf,
    }
}

fn compile(node: &Node, out: &mut Vec<Op>) {
    match node {
        Node::Num(v) => out.push(Op::Const(*v)),
        Node::X => out.push(Op::X),
        Node::Y => out.push(Op::Y),
        Node::R => out.push(Op::R),
        Node::Un(f, a) => {
            compile(a, out);
            out.push(Op::Un(*f));
        }
        Node::Bin(f, a, b) => match (&**a, &**b) {
            (a, Node::Num(c)) => {
                compile(a, out);
                out.push(Op::BinC(*f, *c));
            }
            (Node::Num(c), b) => {
                compile(b, out);
                out.push(Op::CBin(*f, *c));
            }
            (a, b) => {
                compile(a, out);
                compile(b, out);
                out.push(Op::Bin(*f));
            }
        },
        Node::If(c, a, b) => {
            compile(c, out);
            let branch = out.len();
            out.push(Op::Jump(0)); // patched below
            compile(a, out);
            let jump = out.len();
            out.push(Op::Jump(0)); // patched below
            let else_at = out.len() as u32;
            compile(b, out);
            let end_at = out.len() as u32;
            out[branch] = Op::Branch { else_at, end_at };
            out[jump] = Op::Jump(end_at);
        }
        Node::Chain(first, rest) => {
            compile(first, out);
            for (f, b) in rest {
                match b {
                    Node::Num(c) => out.push(Op::BinC(*f, *c)),
                    b => {
                        compile(b, out);
                        out.push(Op::Bin(*f));
                    }
                }
            }
        }
    }
}

// ---------------------------------------------------------------------------------------
// Lexer.

#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Num(f64),
    Ident,
    Plus,
    Minus,
    Star,
    Slash,
    Caret,
    Lt,
    Le,
    Gt,
    Ge,
    EqEq,
    Ne,
    AndAnd,
    OrOr,
    Bang,
    LParen,
    RParen,
    Comma,
    End,
}

#[derive(Clone, Debug)]
struct Token {
    kind: Kind,
    text: String,
    /// Column of the first character, from 1, in characters.
    col: usize,
}

impl Token {
    /// How the token is named in messages.
    fn describe(&self) -> String {
        match self.kind {
            Kind::End => "end of expression".to_string(),
            Kind::Num(_) => format!("number '{}' at column {}", excerpt(&self.text), self.col),
            Kind::Ident => format!("name '{}' at column {}", excerpt(&self.text), self.col),
            _ => format!("'{}' at column {}", self.text, self.col),
        }
    }
}

fn lex(src: &str) -> std::result::Result<Vec<Token>, String> {
    let chars: Vec<char> = src.chars().collect();
    let mut tokens = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let col = i + 1;
        if c.is_whitespace() {
            i += 1;
            continue;
        }
        let start = i;
        let kind = if c.is_ascii_digit()
            || (c == '.' && chars.get(i + 1).is_some_and(char::is_ascii_digit))
        {
            while i < chars.len() && chars[i].is_ascii_digit() {
                i += 1;
            }
            if chars.get(i) == Some(&'.') {
                i += 1;
                while i < chars.len() && chars[i].is_ascii_digit() {
                    i += 1;
                }
            }
            if matches!(chars.get(i), Some('e' | 'E')) {
                let digit_at = match chars.get(i + 1) {
                    Some('+' | '-') => i + 2,
                    _ => i + 1,
                };
                if chars.get(digit_at).is_some_and(char::is_ascii_digit) {
                    i = digit_at;
                    while i < chars.len() && chars[i].is_ascii_digit() {
                        i += 1;
                    }
                }
            }
            let text: String = chars[start..i].iter().collect();
            match text.parse::<f64>() {
                Ok(v) if v.is_finite() => Kind::Num(v),
                _ => {
                    return Err(format!(
                        "number '{}' at column {col} is out of range",
                        excerpt(&text)
                    ))
                }
            }
        } else if c.is_alphabetic() || c == '_' {
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            Kind::Ident
        } else {
            let next = chars.get(i + 1).copied();
            let (kind, len) = match (c, next) {
                ('*', Some('*')) => (Kind::Caret, 2),
                ('<', Some('=')) => (Kind::Le, 2),
                ('>', Some('=')) => (Kind::Ge, 2),
                ('=', Some('=')) => (Kind::EqEq, 2),
                ('!', Some('=')) => (Kind::Ne, 2),
                ('&', Some('&')) => (Kind::AndAnd, 2),
                ('|', Some('|')) => (Kind::OrOr, 2),
                ('+', _) => (Kind::Plus, 1),
                ('-', _) => (Kind::Minus, 1),
                ('*', _) => (Kind::Star, 1),
                ('/', _) => (Kind::Slash, 1),
                ('^', _) => (Kind::Caret, 1),
                ('<', _) => (Kind::Lt, 1),
                ('>', _) => (Kind::Gt, 1),
                ('!', _) => (Kind::Bang, 1),
                ('(', _) => (Kind::LParen, 1),
                (')', _) => (Kind::RParen, 1),
                (',', _) => (Kind::Comma, 1),
                ('=', _) => return Err(format!("'=' at column {col}: write '==' to compare")),
                ('&', _) => return Err(format!("'&' at column {col}: write '&&' for 'and'")),
                ('|', _) => return Err(format!("'|' at column {col}: write '||' for 'or'")),
                _ => return Err(format!("unexpected character '{c}' at column {col}")),
            };
            i += len;
            kind
        };
        tokens.push(Token {
            kind,
            text: chars[start..i].iter().collect(),
            col,
        });
    }
    tokens.push(Token {
        kind: Kind::End,
        text: String::new(),
        col: chars.len() + 1,
    });
    Ok(tokens)
}

// ---------------------------------------------------------------------------------------
// Parser: recursive descent, one function per precedence level.

/// The variables and constants, for messages.
const NAMES_HINT: &str = "the variables are x, y, r; the constants pi, e";
/// The functions, for messages.
const FUNCTIONS_HINT: &str = "the functions are sin, cos, tan, asin, acos, atan, atan2, sinh, cosh, \
     tanh, exp, ln, log, log10, sqrt, abs, min, max, pow, floor, ceil, round, sign, hypot, step, if";

/// What a function name stands for.
#[derive(Clone, Copy)]
enum Function {
    Un(UnOp),
    Bin(BinOp),
    /// `min` and `max`: one or more arguments.
    Fold(BinOp),
    If,
}

fn function(name: &str) -> Option<Function> {
    use Function::*;
    Some(match name {
        "sin" => Un(UnOp::Sin),
        "cos" => Un(UnOp::Cos),
        "tan" => Un(UnOp::Tan),
        "asin" => Un(UnOp::Asin),
        "acos" => Un(UnOp::Acos),
        "atan" => Un(UnOp::Atan),
        "sinh" => Un(UnOp::Sinh),
        "cosh" => Un(UnOp::Cosh),
        "tanh" => Un(UnOp::Tanh),
        "exp" => Un(UnOp::Exp),
        "ln" | "log" => Un(UnOp::Ln),
        "log10" => Un(UnOp::Log10),
        "sqrt" => Un(UnOp::Sqrt),
        "abs" => Un(UnOp::Abs),
        "floor" => Un(UnOp::Floor),
        "ceil" => Un(UnOp::Ceil),
        "round" => Un(UnOp::Round),
        "sign" => Un(UnOp::Sign),
        "step" => Un(UnOp::Step),
        "atan2" => Bin(BinOp::Atan2),
        "pow" => Bin(BinOp::Pow),
        "hypot" => Bin(BinOp::Hypot),
        "min" => Fold(BinOp::Min),
        "max" => Fold(BinOp::Max),
        "if" => If,
        _ => return None,
    })
}

/// A subtree with its depth (bounded by [`MAX_TREE_DEPTH`]).
struct Sub {
    node: Node,
    depth: u32,
}

type PResult = std::result::Result<Sub, String>;

fn leaf(node: Node) -> Sub {
    Sub { node, depth: 1 }
}

fn checked(node: Node, depth: u32, col: usize) -> PResult {
    if depth > MAX_TREE_DEPTH {
        return Err(format!(
            "expression too large at column {col} (its tree is deeper than {MAX_TREE_DEPTH} levels)"
        ));
    }
    Ok(Sub { node, depth })
}

fn un(f: UnOp, a: Sub, col: usize) -> PResult {
    checked(Node::Un(f, Box::new(a.node)), a.depth + 1, col)
}

fn bin(f: BinOp, a: Sub, b: Sub, col: usize) -> PResult {
    let depth = a.depth.max(b.depth) + 1;
    checked(Node::Bin(f, Box::new(a.node), Box::new(b.node)), depth, col)
}

/// `first op₁ b op₂ c …` (left to right) as one flat node: its depth is that of its
/// deepest term plus one, whatever the number of terms.
fn chain(first: Sub, rest: Vec<(BinOp, Sub)>, col: usize) -> PResult {
    let mut depth = first.depth;
    let mut terms = Vec::with_capacity(rest.len());
    for (f, b) in rest {
        depth = depth.max(b.depth);
        terms.push((f, b.node));
    }
    match terms.len() {
        0 => Ok(first),
        1 => {
            let (f, b) = terms.pop().expect("one term");
            checked(
                Node::Bin(f, Box::new(first.node), Box::new(b)),
                depth + 1,
                col,
            )
        }
        _ => checked(Node::Chain(Box::new(first.node), terms), depth + 1, col),
    }
}

fn cond(c: Sub, a: Sub, b: Sub, col: usize) -> PResult {
    let depth = c.depth.max(a.depth).max(b.depth) + 1;
    checked(
        Node::If(Box::new(c.node), Box::new(a.node), Box::new(b.node)),
        depth,
        col,
    )
}

struct Parser {
    tokens: Vec<Token>,
    pos: usize,
    nesting: usize,
}

impl Parser {
    fn peek(&self) -> &Token {
        // The token list always ends with `End`, and `pos` never passes it.
        &self.tokens[self.pos.min(self.tokens.len() - 1)]
    }

    fn next(&mut self) -> Token {
        let t = self.peek().clone();
        if t.kind != Kind::End {
            self.pos += 1;
        }
        t
    }

    /// The token before the current one, if any.
    fn previous(&self) -> Option<&Token> {
        self.pos.checked_sub(1).and_then(|i| self.tokens.get(i))
    }

    /// Parentheses opened and not closed before the token just consumed.
    fn open_parens_before_previous(&self) -> i64 {
        let end = self.pos.saturating_sub(1);
        self.tokens[..end].iter().fold(0, |n, t| match t.kind {
            Kind::LParen => n + 1,
            Kind::RParen => n - 1,
            _ => n,
        })
    }

    fn parse_all(mut self) -> PResult {
        if self.peek().kind == Kind::End {
            return Err("empty expression".to_string());
        }
        let tree = self.or()?;
        let t = self.peek();
        match t.kind {
            Kind::End => Ok(tree),
            Kind::RParen => Err(format!(
                "unbalanced parenthesis: ')' at column {} has no matching '('",
                t.col
            )),
            _ => Err(format!(
                "unexpected {} after a complete expression (missing operator?)",
                t.describe()
            )),
        }
    }

    fn or(&mut self) -> PResult {
        let mut a = self.and()?;
        while self.peek().kind == Kind::OrOr {
            let col = self.next().col;
            let b = self.and()?;
            // a || b = if(a, 1, truthy(b)): b is not evaluated when a holds.
            let b = un(UnOp::Truthy, b, col)?;
            a = cond(a, leaf(Node::Num(1.0)), b, col)?;
        }
        Ok(a)
    }

    fn and(&mut self) -> PResult {
        let mut a = self.equality()?;
        while self.peek().kind == Kind::AndAnd {
            let col = self.next().col;
            let b = self.equality()?;
            // a && b = if(a, truthy(b), 0): b is not evaluated when a fails.
            let b = un(UnOp::Truthy, b, col)?;
            a = cond(a, b, leaf(Node::Num(0.0)), col)?;
        }
        Ok(a)
    }

    fn equality(&mut self) -> PResult {
        let a = self.comparison()?;
        let f = match self.peek().kind {
            Kind::EqEq => BinOp::Eq,
            Kind::Ne => BinOp::Ne,
            _ => return Ok(a),
        };
        let op = self.next();
        let b = self.comparison()?;
        let t = self.peek();
        if matches!(t.kind, Kind::EqEq | Kind::Ne) {
            return Err(format!(
                "chained comparison: '{}' at column {} follows '{}' at column {} (use parentheses)",
                t.text, t.col, op.text, op.col
            ));
        }
        bin(f, a, b, op.col)
    }

    fn comparison(&mut self) -> PResult {
        let a = self.sum()?;
        let f = match self.peek().kind {
            Kind::Lt => BinOp::Lt,
            Kind::Le => BinOp::Le,
            Kind::Gt => BinOp::Gt,
            Kind::Ge => BinOp::Ge,
            _ => return Ok(a),
        };
        let op = self.next();
        let b = self.sum()?;
        let t = self.peek();
        if matches!(t.kind, Kind::Lt | Kind::Le | Kind::Gt | Kind::Ge) {
            return Err(format!(
                "chained comparison: '{}' at column {} follows '{}' at column {} \
                 (write a < b && b < c)",
                t.text, t.col, op.text, op.col
            ));
        }
        bin(f, a, b, op.col)
    }

    /// Terms joined by `+` and `-`: one flat chain, however many.
    fn sum(&mut self) -> PResult {
        let col = self.peek().col;
        let a = self.product()?;
        let mut rest = Vec::new();
        loop {
            let f = match self.peek().kind {
                Kind::Plus => BinOp::Add,
                Kind::Minus => BinOp::Sub,
                _ => return chain(a, rest, col),
            };
            self.next();
            rest.push((f, self.product()?));
        }
    }

    /// Factors joined by `*` and `/`: one flat chain, however many.
    fn product(&mut self) -> PResult {
        let col = self.peek().col;
        let a = self.unary()?;
        let mut rest = Vec::new();
        loop {
            let f = match self.peek().kind {
                Kind::Star => BinOp::Mul,
                Kind::Slash => BinOp::Div,
                _ => return chain(a, rest, col),
            };
            self.next();
            rest.push((f, self.unary()?));
        }
    }

    fn unary(&mut self) -> PResult {
        self.nesting += 1;
        let result = if self.nesting > MAX_NESTING {
            Err(format!(
                "expression nested too deeply at column {} (more than {MAX_NESTING} levels)",
                self.peek().col
            ))
        } else {
            self.unary_inner()
        };
        self.nesting -= 1;
        result
    }

    fn unary_inner(&mut self) -> PResult {
        let f = match self.peek().kind {
            Kind::Minus => UnOp::Neg,
            Kind::Bang => UnOp::Not,
            Kind::Plus => {
                self.next();
                return self.unary();
            }
            _ => return self.power(),
        };
        let col = self.next().col;
        let a = self.unary()?;
        un(f, a, col)
    }

    fn power(&mut self) -> PResult {
        let base = self.primary()?;
        if self.peek().kind != Kind::Caret {
            return Ok(base);
        }
        let col = self.next().col;
        // The exponent may carry a sign (2^-1) and is itself a power: right-associative.
        let exponent = self.unary()?;
        bin(BinOp::Pow, base, exponent, col)
    }

    fn primary(&mut self) -> PResult {
        let t = self.next();
        match t.kind {
            Kind::Num(v) => Ok(leaf(Node::Num(v))),
            Kind::Ident => self.name(t),
            Kind::LParen => {
                let inner = self.or()?;
                self.close(&t)?;
                Ok(inner)
            }
            Kind::End => {
                let after = match self.previous() {
                    Some(p) => format!(" after '{}' at column {}", excerpt(&p.text), p.col),
                    None => String::new(),
                };
                Err(format!(
                    "unexpected end of expression{after} (expected a number, a variable, a function call or '(')"
                ))
            }
            Kind::RParen if self.open_parens_before_previous() <= 0 => Err(format!(
                "unbalanced parenthesis: ')' at column {} has no matching '('",
                t.col
            )),
            _ => Err(format!(
                "unexpected {} (expected a number, a variable, a function call or '(')",
                t.describe()
            )),
        }
    }

    /// Consumes the ')' matching `open`.
    fn close(&mut self, open: &Token) -> std::result::Result<(), String> {
        let t = self.next();
        match t.kind {
            Kind::RParen => Ok(()),
            Kind::End => Err(format!(
                "unbalanced parenthesis: '(' at column {} is never closed",
                open.col
            )),
            _ => Err(format!(
                "expected ')' to close '(' at column {}, found {}",
                open.col,
                t.describe()
            )),
        }
    }

    /// A variable, a constant or a function call.
    fn name(&mut self, t: Token) -> PResult {
        let name = t.text.as_str();
        if self.peek().kind != Kind::LParen {
            return Ok(leaf(match name {
                "x" => Node::X,
                "y" => Node::Y,
                "r" => Node::R,
                "pi" => Node::Num(std::f64::consts::PI),
                "e" => Node::Num(std::f64::consts::E),
                _ if function(name).is_some() => {
                    return Err(format!(
                        "'{name}' at column {} is a function: write {name}(...)",
                        t.col
                    ))
                }
                _ => {
                    return Err(format!(
                        "unknown variable '{}' at column {} ({NAMES_HINT})",
                        excerpt(name),
                        t.col
                    ))
                }
            }));
        }
        let Some(f) = function(name) else {
            return Err(match name {
                "x" | "y" | "r" | "pi" | "e" => format!(
                    "'{name}' at column {} is not a function (missing '*' before '('?)",
                    t.col
                ),
                _ => format!(
                    "unknown function '{}' at column {} ({FUNCTIONS_HINT})",
                    excerpt(name),
                    t.col
                ),
            });
        };
        let open = self.next();
        let mut args = Vec::new();
        if self.peek().kind != Kind::RParen {
            loop {
                args.push(self.or()?);
                if self.peek().kind != Kind::Comma {
                    break;
                }
                self.next();
            }
        }
        self.close(&open)?;
        let n = args.len();
        let arity_error = |expected: &str| {
            Err(format!(
                "{name} expects {expected}, got {n} (at column {})",
                t.col
            ))
        };
        let mut args = args.into_iter();
        match f {
            Function::Un(f) => match (args.next(), n) {
                (Some(a), 1) => un(f, a, t.col),
                _ => arity_error("1 argument"),
            },
            Function::Bin(f) => match (args.next(), args.next(), n) {
                (Some(a), Some(b), 2) => bin(f, a, b, t.col),
                _ => arity_error("2 arguments"),
            },
            Function::If => match (args.next(), args.next(), args.next(), n) {
                (Some(c), Some(a), Some(b), 3) => cond(c, a, b, t.col),
                _ => arity_error("3 arguments (condition, value if true, value if false)"),
            },
            Function::Fold(f) => {
                let Some(first) = args.next() else {
                    return arity_error("at least 1 argument");
                };
                chain(first, args.map(|b| (f, b)).collect(), t.col)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{E, PI};

    fn v(src: &str, x: f64, y: f64) -> f64 {
        Expr::parse(src)
            .unwrap_or_else(|e| panic!("{src}: {e}"))
            .eval(x, y)
    }

    fn c(src: &str) -> f64 {
        v(src, 0.0, 0.0)
    }

    fn err(src: &str) -> String {
        match Expr::parse(src) {
            Ok(e) => panic!("{src:?} parsed as {e:?}"),
            Err(Error::Expr { expr, message }) => {
                assert_eq!(expr, src);
                message
            }
            Err(other) => panic!("{src:?}: wrong error kind {other:?}"),
        }
    }

    fn assert_err(src: &str, fragments: &[&str]) {
        let message = err(src);
        for f in fragments {
            assert!(message.contains(f), "{src:?}: {message:?} lacks {f:?}");
        }
    }

    #[test]
    fn numbers_variables_and_constants() {
        assert_eq!(c("1"), 1.0);
        assert_eq!(c("2.5"), 2.5);
        assert_eq!(c("1e-3"), 1e-3);
        assert_eq!(c("1E+3"), 1000.0);
        assert_eq!(c(".5"), 0.5);
        assert_eq!(c("3."), 3.0);
        assert_eq!(c("pi"), PI);
        assert_eq!(c("e"), E);
        assert_eq!(v("x", 3.0, 4.0), 3.0);
        assert_eq!(v("y", 3.0, 4.0), 4.0);
        assert_eq!(v("r", 3.0, 4.0), 5.0);
        assert_eq!(v("r", -3.0, -4.0), 5.0);
        assert_eq!(v(" \tx\n", 7.0, 0.0), 7.0);
    }

    #[test]
    fn precedence_and_associativity() {
        assert_eq!(c("1 + 2 * 3"), 7.0);
        assert_eq!(c("(1 + 2) * 3"), 9.0);
        assert_eq!(c("10 - 4 - 3"), 3.0);
        assert_eq!(c("8 / 4 / 2"), 1.0);
        assert_eq!(c("2 * 3 / 4"), 1.5);
        assert_eq!(c("-2^2"), -4.0);
        assert_eq!(c("(-2)^2"), 4.0);
        assert_eq!(c("2^3^2"), 512.0);
        assert_eq!(c("2**3**2"), 512.0);
        assert_eq!(c("2^-1"), 0.5);
        assert_eq!(c("-2^-2"), -0.25);
        assert_eq!(c("2 * -3"), -6.0);
        assert_eq!(c("--3"), 3.0);
        assert_eq!(c("+3 - +2"), 1.0);
        assert_eq!(v("-x^2", 3.0, 0.0), -9.0);
        assert_eq!(v("2*x^2 + 1", 3.0, 0.0), 19.0);
        assert_eq!(c("1 + 2 < 4"), 1.0); // (1 + 2) < 4
        assert_eq!(c("1 < 2 == 1"), 1.0); // (1 < 2) == 1
        assert_eq!(c("0 || 1 && 0"), 0.0); // 0 || (1 && 0)
        assert_eq!(c("1 || 1 && 0"), 1.0);
        assert_eq!(c("!0 + 1"), 2.0); // (!0) + 1
        assert_eq!(c("!2 == 0"), 1.0); // (!2) == 0
        assert_eq!(c("3 - 2 > 0 && 1"), 1.0);
    }

    #[test]
    fn comparisons_and_logic() {
        for (src, want) in [
            ("1 < 2", 1.0),
            ("2 < 1", 0.0),
            ("2 <= 2", 1.0),
            ("3 <= 2", 0.0),
            ("3 > 2", 1.0),
            ("2 > 2", 0.0),
            ("2 >= 2", 1.0),
            ("1 >= 2", 0.0),
            ("2 == 2", 1.0),
            ("2 == 3", 0.0),
            ("2 != 3", 1.0),
            ("2 != 2", 0.0),
            ("!0", 1.0),
            ("!3", 0.0),
            ("!!5", 1.0),
            ("1 && 0", 0.0),
            ("2 && -3", 1.0),
            ("0 && 1", 0.0),
            ("0 || 0", 0.0),
            ("0 || 2", 1.0),
            ("5 || 0", 1.0),
        ] {
            assert_eq!(c(src), want, "{src}");
        }
        // A disc indicator and a square indicator.
        let disc = Expr::parse("x^2 + y^2 < 0.25").unwrap();
        assert_eq!(disc.eval(0.1, 0.2), 1.0);
        assert_eq!(disc.eval(0.5, 0.5), 0.0);
        let square = Expr::parse("abs(x) <= 1 && abs(y) <= 1").unwrap();
        assert_eq!(square.eval(1.0, -0.5), 1.0);
        assert_eq!(square.eval(1.0, -1.5), 0.0);
    }

    #[test]
    fn functions_against_std() {
        let x: f64 = 0.37;
        let y: f64 = -1.9;
        let cases: [(&str, f64); 26] = [
            ("sin(x)", x.sin()),
            ("cos(y)", y.cos()),
            ("tan(x)", x.tan()),
            ("asin(x)", x.asin()),
            ("acos(x)", x.acos()),
            ("atan(y)", y.atan()),
            ("atan2(y, x)", y.atan2(x)),
            ("sinh(y)", y.sinh()),
            ("cosh(y)", y.cosh()),
            ("tanh(y)", y.tanh()),
            ("exp(y)", y.exp()),
            ("ln(x)", x.ln()),
            ("log(x)", x.ln()),
            ("log10(x)", x.log10()),
            ("sqrt(x)", x.sqrt()),
            ("abs(y)", 1.9),
            ("pow(x, y)", x.powf(y)),
            ("x ^ y", x.powf(y)),
            ("hypot(x, y)", x.hypot(y)),
            ("floor(y)", -2.0),
            ("ceil(y)", -1.0),
            ("round(y)", -2.0),
            ("min(x, y, 0)", y),
            ("max(x, y, 0)", x),
            ("min(y)", y),
            ("sign(y)", -1.0),
        ];
        for (src, want) in cases {
            assert_eq!(v(src, x, y), want, "{src}");
        }
        assert_eq!(c("sin(pi/2)"), 1.0);
        assert_eq!(c("cos(0)"), 1.0);
        assert!((c("atan2(1, -1)") - 3.0 * PI / 4.0).abs() < 1e-15);
        assert_eq!(c("hypot(3, 4)"), 5.0);
        assert_eq!(c("exp(1)"), E);
        assert_eq!(c("ln(e)"), 1.0);
        assert_eq!(c("log10(1000)"), 3.0);
        assert_eq!(c("sqrt(16)"), 4.0);
        assert_eq!(c("pow(2, 10)"), 1024.0);
        assert_eq!(c("round(2.5)"), 3.0);
        assert_eq!(c("round(-2.5)"), -3.0);
        assert_eq!(c("sign(3)"), 1.0);
        assert_eq!(c("sign(0)"), 0.0);
        assert_eq!(c("step(0)"), 1.0);
        assert_eq!(c("step(2)"), 1.0);
        assert_eq!(c("step(-1e-300)"), 0.0);
        assert_eq!(c("max(1, 5, 3, 4)"), 5.0);
        assert_eq!(c("min(4, 2, 3)"), 2.0);
        assert_eq!(v("x^2", -3.0, 0.0), 9.0);
    }

    #[test]
    fn if_is_lazy_and_nan_never_leaks() {
        let e = Expr::parse("if(x > 0, sqrt(x), 0)").unwrap();
        assert_eq!(e.eval(4.0, 0.0), 2.0);
        assert_eq!(e.eval(-4.0, 0.0), 0.0);
        let e = Expr::parse("if(x < 0, -1, ln(x))").unwrap();
        assert_eq!(e.eval(-1.0, 0.0), -1.0);
        assert_eq!(e.eval(E, 0.0), 1.0);
        // Nested ifs: a piecewise function.
        let e = Expr::parse("if(x < 1, 10, if(x < 2, 20, 30)) + y").unwrap();
        assert_eq!(e.eval(0.5, 1.0), 11.0);
        assert_eq!(e.eval(1.5, 1.0), 21.0);
        assert_eq!(e.eval(2.5, 1.0), 31.0);
        // && and || do not evaluate their right side when the left decides.
        let e = Expr::parse("x >= 0 && sqrt(x) > 1").unwrap();
        assert_eq!(e.eval(-4.0, 0.0), 0.0);
        assert_eq!(e.eval(4.0, 0.0), 1.0);
        assert_eq!(e.eval(0.25, 0.0), 0.0);
        let e = Expr::parse("x < 0 || sqrt(x) > 1").unwrap();
        assert_eq!(e.eval(-4.0, 0.0), 1.0);
        assert_eq!(e.eval(4.0, 0.0), 1.0);
        assert_eq!(e.eval(0.25, 0.0), 0.0);
        // A NaN actually reached propagates instead of being read as true or false.
        for src in [
            "if(sqrt(x), 1, 2)",
            "sqrt(x) < 1",
            "sqrt(x) == sqrt(x)",
            "!sqrt(x)",
            "min(sqrt(x), 1)",
            "max(1, sqrt(x))",
            "sign(sqrt(x))",
            "step(sqrt(x))",
            "sqrt(x) && 1",
            "1 && sqrt(x)",
            "0 || sqrt(x)",
        ] {
            assert!(v(src, -1.0, 0.0).is_nan(), "{src}");
        }
        assert!(c("if(0/0, 1, 2)").is_nan());
    }

    #[test]
    fn constant_folding() {
        for (src, want) in [
            ("2*pi", 2.0 * PI),
            ("sin(pi/2)", 1.0),
            ("-3", -3.0),
            ("1e-3", 1e-3),
            ("if(1, 3, x)", 3.0),
            ("if(0, x, 2)", 2.0),
            ("min(1, 2) + max(3, 4)^2", 17.0),
            ("0 && x", 0.0),
            ("1 || y", 1.0),
        ] {
            let e = Expr::parse(src).unwrap();
            assert_eq!(e.constant_value(), Some(want), "{src}");
            assert_eq!(e.eval(0.3, 0.7), want, "{src}");
        }
        for src in ["x", "0*x", "y - 1", "r", "if(x, 1, 1)", "2*pi*x", "1 && x"] {
            assert_eq!(Expr::parse(src).unwrap().constant_value(), None, "{src}");
        }
        assert!(Expr::parse("sqrt(-1)")
            .unwrap()
            .constant_value()
            .unwrap()
            .is_nan());
        assert_eq!(Expr::parse("x").unwrap().source(), "x");
    }

    #[test]
    fn the_benchmark_expression() {
        let e = Expr::parse("0.5 + 0.1*sin(2*pi*x)*cos(2*pi*y)").unwrap();
        for (x, y) in [(0.0, 0.0), (0.25, 0.0), (0.3, 0.8), (-1.7, 2.2)] {
            let want = 0.5 + 0.1 * (2.0 * PI * x).sin() * (2.0 * PI * y).cos();
            assert_eq!(e.eval(x, y), want);
        }
    }

    #[test]
    fn error_messages_name_the_problem_and_the_column() {
        assert_err("1 + z", &["unknown variable 'z' at column 5", "x, y, r"]);
        assert_err("π + z", &["unknown variable 'π' at column 1"]);
        assert_err("x + π", &["unknown variable 'π' at column 5"]);
        assert_err("X", &["unknown variable 'X'"]);
        assert_err(
            "2 * foo(x)",
            &["unknown function 'foo' at column 5", "sin, cos"],
        );
        assert_err("sin(1, 2)", &["sin expects 1 argument, got 2"]);
        assert_err("sin()", &["sin expects 1 argument, got 0"]);
        assert_err("atan2(1)", &["atan2 expects 2 arguments, got 1"]);
        assert_err("pow(1, 2, 3)", &["pow expects 2 arguments, got 3"]);
        assert_err("if(1, 2)", &["if expects 3 arguments", "got 2"]);
        assert_err("min()", &["min expects at least 1 argument, got 0"]);
        assert_err(
            "1 +",
            &["unexpected end of expression", "after '+' at column 3"],
        );
        assert_err("sin(", &["unexpected end of expression"]);
        assert_err(
            "(1 + 2",
            &["unbalanced parenthesis", "'(' at column 1 is never closed"],
        );
        assert_err("sin(x", &["unbalanced parenthesis", "column 4"]);
        assert_err("1 + 2)", &["unbalanced parenthesis", "')' at column 6"]);
        assert_err(")", &["unbalanced parenthesis", "')' at column 1"]);
        assert_err("(1) + )", &["unbalanced parenthesis", "')' at column 7"]);
        assert_err("(1 +)", &["unexpected ')' at column 5"]);
        assert_err("min(1,)", &["unexpected ')' at column 7"]);
        assert_err("()", &["unexpected ')' at column 2"]);
        assert_err("", &["empty expression"]);
        assert_err("  \t ", &["empty expression"]);
        assert_err(
            "2 x",
            &["unexpected name 'x' at column 3", "missing operator"],
        );
        assert_err("2x", &["unexpected name 'x' at column 2"]);
        assert_err("1.2.3", &["unexpected number '.3' at column 4"]);
        assert_err("1, 2", &["unexpected ',' at column 2"]);
        assert_err(
            "(1 2)",
            &[
                "expected ')' to close '(' at column 1",
                "number '2' at column 4",
            ],
        );
        assert_err("* 2", &["unexpected '*' at column 1"]);
        assert_err("1 = 2", &["'=' at column 3", "=="]);
        assert_err("1 & 2", &["'&' at column 3", "&&"]);
        assert_err("1 | 2", &["'|' at column 3", "||"]);
        assert_err("1 # 2", &["unexpected character '#' at column 3"]);
        assert_err("0 < x < 1", &["chained comparison", "column 7"]);
        assert_err("1 == 1 == 1", &["chained comparison"]);
        assert_err("sin + 1", &["'sin' at column 1 is a function"]);
        assert_err("x(2)", &["'x' at column 1 is not a function"]);
        assert_err("1e999", &["number '1e999' at column 1 is out of range"]);
        // The error displays with the expression.
        let shown = Expr::parse("1 + z").unwrap_err().to_string();
        assert!(
            shown.starts_with("expression `1 + z`: unknown variable 'z'"),
            "{shown}"
        );
    }

    #[test]
    fn deep_and_long_inputs_are_errors_not_crashes() {
        let n = 100_000;
        let parens = format!("{}1{}", "(".repeat(n), ")".repeat(n));
        assert_err(&parens, &["nested too deeply"]);
        assert_err(&format!("{}1", "-".repeat(n)), &["nested too deeply"]);
        assert_err(&format!("{}1", "2^".repeat(n)), &["nested too deeply"]);
        assert_err(&format!("{}1", "sin(".repeat(n)), &["nested too deeply"]);
        // Flat sums, products and min/max of any length are chains, not deep trees.
        assert_eq!(c(&format!("{}1", "1+".repeat(n))), (n + 1) as f64);
        assert_eq!(
            v(&format!("{}x", "x+".repeat(n)), 2.0, 0.0),
            2.0 * (n + 1) as f64
        );
        assert_eq!(v(&format!("{}1", "x*".repeat(n)), 1.0, 0.0), 1.0);
        assert_eq!(v(&format!("min({}x)", "1,".repeat(n)), 0.5, 0.0), 0.5);
        assert_eq!(v(&format!("x{}", "-1+2".repeat(n)), 0.0, 0.0), n as f64);
        // The deep nesting left is refused, with a message that quotes the beginning
        // of the expression only.
        let deep = format!("{}1{}", "(1+".repeat(1001), ")".repeat(1001));
        let e = Expr::parse(&deep).unwrap_err().to_string();
        assert!(e.contains("too") && e.len() < 400, "{e}");
        let long = format!("{}q", "x+".repeat(200_000));
        let e = Expr::parse(&long).unwrap_err().to_string();
        assert!(e.contains("unknown variable 'q'") && e.len() < 400, "{e}");
        assert!(e.contains("400001 characters"), "{e}");
        let e = Expr::parse(&format!("1{}", "1".repeat(400)))
            .unwrap_err()
            .to_string();
        assert!(e.contains("out of range") && e.len() < 400, "{e}");
        // Within the limits all is well.
        let ok = format!("{}x{}", "(".repeat(100), ")".repeat(100));
        assert_eq!(v(&ok, 2.0, 0.0), 2.0);
        let sum = format!("{}x", "1+".repeat(500));
        assert_eq!(v(&sum, 2.0, 0.0), 502.0);
        // A program deeper than the inline stack evaluates on the heap.
        let right_deep = format!("{}x{}", "x+(".repeat(60), ")".repeat(60));
        assert_eq!(v(&right_deep, 1.0, 0.0), 61.0);
    }

    #[test]
    fn thread_safe() {
        fn check<T: Send + Sync + Clone + std::fmt::Debug>() {}
        check::<Expr>();
    }

    // ---- random expressions against Rust closures ----

    /// splitmix64: a small deterministic generator for the tests.
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> u64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^ (z >> 31)
        }
        fn below(&mut self, n: usize) -> usize {
            (self.next() % n as u64) as usize
        }
        fn unit(&mut self) -> f64 {
            (self.next() >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// A random expression: its text (minimal parentheses, so that precedence is tested)
    /// and its value by plain Rust arithmetic.
    enum Gen {
        Num(f64),
        X,
        Y,
        R,
        Neg(Box<Gen>),
        Not(Box<Gen>),
        Call(&'static str, Vec<Gen>),
        /// Infix operator with its precedence level.
        Infix(&'static str, u8, Box<Gen>, Box<Gen>),
    }

    const INFIX: [(&str, u8); 15] = [
        ("||", 1),
        ("&&", 2),
        ("==", 3),
        ("!=", 3),
        ("<", 4),
        ("<=", 4),
        (">", 4),
        (">=", 4),
        ("+", 5),
        ("-", 5),
        ("*", 6),
        ("/", 6),
        ("^", 8),
        ("*", 6),
        ("+", 5),
    ];
    const UNARY_PREC: u8 = 7;
    const FUNCS: [(&str, usize); 22] = [
        ("sin", 1),
        ("cos", 1),
        ("tan", 1),
        ("atan", 1),
        ("asin", 1),
        ("exp", 1),
        ("ln", 1),
        ("sqrt", 1),
        ("abs", 1),
        ("floor", 1),
        ("round", 1),
        ("sign", 1),
        ("step", 1),
        ("tanh", 1),
        ("atan2", 2),
        ("hypot", 2),
        ("pow", 2),
        ("min", 1),
        ("min", 3),
        ("max", 2),
        ("if", 3),
        ("log10", 1),
    ];

    fn gen(rng: &mut Rng, depth: usize) -> Gen {
        if depth == 0 || rng.below(5) == 0 {
            return match rng.below(5) {
                0 => Gen::X,
                1 => Gen::Y,
                2 => Gen::R,
                _ => Gen::Num([0.0, 1.0, 2.0, 0.5, 3.25, 1e-3, 10.0][rng.below(7)]),
            };
        }
        match rng.below(10) {
            0 => Gen::Neg(Box::new(gen(rng, depth - 1))),
            1 => Gen::Not(Box::new(gen(rng, depth - 1))),
            2..=4 => {
                let (name, n) = FUNCS[rng.below(FUNCS.len())];
                Gen::Call(name, (0..n).map(|_| gen(rng, depth - 1)).collect())
            }
            _ => {
                let (op, prec) = INFIX[rng.below(INFIX.len())];
                Gen::Infix(
                    op,
                    prec,
                    Box::new(gen(rng, depth - 1)),
                    Box::new(gen(rng, depth - 1)),
                )
            }
        }
    }

    fn prec(g: &Gen) -> u8 {
        match g {
            Gen::Neg(_) | Gen::Not(_) => UNARY_PREC,
            Gen::Infix(_, p, ..) => *p,
            _ => 10,
        }
    }

    fn text(g: &Gen) -> String {
        let wrap = |child: &Gen, need: bool| {
            if need {
                format!("({})", text(child))
            } else {
                text(child)
            }
        };
        match g {
            Gen::Num(v) => format!("{v}"),
            Gen::X => "x".into(),
            Gen::Y => "y".into(),
            Gen::R => "r".into(),
            Gen::Neg(a) => format!("-{}", wrap(a, prec(a) < UNARY_PREC)),
            Gen::Not(a) => format!("!{}", wrap(a, prec(a) < UNARY_PREC)),
            Gen::Call(name, args) => {
                let args: Vec<String> = args.iter().map(text).collect();
                format!("{name}({})", args.join(", "))
            }
            Gen::Infix(op, p, a, b) => {
                let (pa, pb) = (prec(a), prec(b));
                let (left, right) = match *p {
                    // Right-associative; the base binds tighter than a unary minus.
                    8 => (pa <= 8, pb < UNARY_PREC),
                    // Comparisons do not chain.
                    3 | 4 => (pa <= *p, pb <= *p),
                    _ => (pa < *p, pb <= *p),
                };
                format!("{} {op} {}", wrap(a, left), wrap(b, right))
            }
        }
    }

    fn nan_or(a: f64, b: f64, f: impl Fn(f64, f64) -> bool) -> f64 {
        if a.is_nan() || b.is_nan() {
            f64::NAN
        } else if f(a, b) {
            1.0
        } else {
            0.0
        }
    }

    fn truthy(v: f64) -> f64 {
        if v.is_nan() {
            v
        } else if v != 0.0 {
            1.0
        } else {
            0.0
        }
    }

    fn value(g: &Gen, x: f64, y: f64) -> f64 {
        let val = |g: &Gen| value(g, x, y);
        match g {
            Gen::Num(v) => *v,
            Gen::X => x,
            Gen::Y => y,
            Gen::R => (x * x + y * y).sqrt(),
            Gen::Neg(a) => -val(a),
            Gen::Not(a) => {
                let a = val(a);
                if a.is_nan() {
                    a
                } else {
                    (a == 0.0) as u8 as f64
                }
            }
            Gen::Call(name, args) => {
                let a: Vec<f64> = match *name {
                    "if" => vec![],
                    _ => args.iter().map(val).collect(),
                };
                match *name {
                    "sin" => a[0].sin(),
                    "cos" => a[0].cos(),
                    "tan" => a[0].tan(),
                    "atan" => a[0].atan(),
                    "asin" => a[0].asin(),
                    "exp" => a[0].exp(),
                    "ln" => a[0].ln(),
                    "log10" => a[0].log10(),
                    "sqrt" => a[0].sqrt(),
                    "abs" => a[0].abs(),
                    "floor" => a[0].floor(),
                    "round" => a[0].round(),
                    "tanh" => a[0].tanh(),
                    "sign" if a[0] == 0.0 || a[0].is_nan() => a[0],
                    "sign" => a[0].signum(),
                    "step" if a[0].is_nan() => a[0],
                    "step" => (a[0] >= 0.0) as u8 as f64,
                    "atan2" => a[0].atan2(a[1]),
                    "hypot" => a[0].hypot(a[1]),
                    "pow" => a[0].powf(a[1]),
                    "min" | "max" => {
                        if a.iter().any(|v| v.is_nan()) {
                            f64::NAN
                        } else if *name == "min" {
                            a.iter().copied().fold(f64::INFINITY, f64::min)
                        } else {
                            a.iter().copied().fold(f64::NEG_INFINITY, f64::max)
                        }
                    }
                    "if" => {
                        let c = val(&args[0]);
                        if c.is_nan() {
                            c
                        } else if c != 0.0 {
                            val(&args[1])
                        } else {
                            val(&args[2])
                        }
                    }
                    other => unreachable!("{other}"),
                }
            }
            Gen::Infix(op, _, a, b) => {
                let u = val(a);
                match *op {
                    "&&" if u.is_nan() => u,
                    "&&" if u == 0.0 => 0.0,
                    "&&" => truthy(val(b)),
                    "||" if u.is_nan() => u,
                    "||" if u != 0.0 => 1.0,
                    "||" => truthy(val(b)),
                    _ => {
                        let w = val(b);
                        match *op {
                            "+" => u + w,
                            "-" => u - w,
                            "*" => u * w,
                            "/" => u / w,
                            "^" => u.powf(w),
                            "<" => nan_or(u, w, |p, q| p < q),
                            "<=" => nan_or(u, w, |p, q| p <= q),
                            ">" => nan_or(u, w, |p, q| p > q),
                            ">=" => nan_or(u, w, |p, q| p >= q),
                            "==" => nan_or(u, w, |p, q| p == q),
                            "!=" => nan_or(u, w, |p, q| p != q),
                            other => unreachable!("{other}"),
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn random_expressions_match_rust_closures() {
        let mut rng = Rng(42);
        let mut checked = 0;
        for _ in 0..3000 {
            let g = gen(&mut rng, 5);
            let src = text(&g);
            let e = Expr::parse(&src).unwrap_or_else(|e| panic!("{src}: {e}"));
            for _ in 0..5 {
                let x = 4.0 * rng.unit() - 2.0;
                let y = 4.0 * rng.unit() - 2.0;
                let (got, want) = (e.eval(x, y), value(&g, x, y));
                assert!(
                    got == want || (got.is_nan() && want.is_nan()),
                    "{src} at ({x}, {y}): got {got}, want {want}"
                );
                checked += !want.is_nan() as usize;
            }
        }
        assert!(checked > 5000, "too few finite cases: {checked}");
    }

    #[test]
    fn many_points_at_once_give_each_point_s_value() {
        let mut rng = Rng(11);
        let special = [
            0.0,
            -0.0,
            f64::NAN,
            f64::INFINITY,
            -f64::INFINITY,
            1e308,
            -1.0,
        ];
        let mut sources: Vec<String> = (0..1500).map(|_| text(&gen(&mut rng, 5))).collect();
        // Constant, with r, with an `if` (point by point), deeper than the lanes' stack.
        let deep = format!("{}1{}", "(x + ".repeat(30), ")".repeat(30));
        sources
            .extend(["2*pi", "r^2 - x*y", "if(x < 0, sin(y), exp(-r))", &deep].map(String::from));
        for src in &sources {
            let e = Expr::parse(src).unwrap_or_else(|e| panic!("{src}: {e}"));
            let n = 1 + rng.below(20);
            let points: Vec<[f64; 2]> = (0..n)
                .map(|_| {
                    let mut q = || {
                        if rng.below(8) == 0 {
                            special[rng.below(special.len())]
                        } else {
                            4.0 * rng.unit() - 2.0
                        }
                    };
                    [q(), q()]
                })
                .collect();
            let mut got = vec![0.0; n];
            e.eval_many(&points, &mut got);
            for (p, g) in points.iter().zip(&got) {
                let want = e.eval(p[0], p[1]);
                assert!(
                    g.to_bits() == want.to_bits() || (g.is_nan() && want.is_nan()),
                    "{src} at {p:?}: {g} at once, {want} alone"
                );
            }
        }
    }

    #[test]
    fn random_garbage_never_panics() {
        const PIECES: [&str; 36] = [
            "x", "y", "r", "pi", "e", "1", "2.5", ".5", "1e3", "e-", "+", "-", "*", "/", "^", "**",
            "(", ")", ",", "<", "<=", "==", "=", "!", "!=", "&&", "||", "&", " ", "sin", "min",
            "if", "atan2", "foo", "é", "9e99999",
        ];
        let mut rng = Rng(7);
        let mut parsed = 0;
        for _ in 0..20_000 {
            let n = 1 + rng.below(12);
            let src: String = (0..n).map(|_| PIECES[rng.below(PIECES.len())]).collect();
            if let Ok(e) = Expr::parse(&src) {
                parsed += 1;
                let _ = e.eval(rng.unit(), -rng.unit());
            }
        }
        assert!(parsed > 100, "only {parsed} parsed");
        // Mutations of valid expressions: drop, duplicate or replace one character.
        for _ in 0..3000 {
            let mut chars: Vec<char> = text(&gen(&mut rng, 4)).chars().collect();
            let i = rng.below(chars.len());
            match rng.below(3) {
                0 => {
                    chars.remove(i);
                }
                1 => chars.insert(i, chars[i]),
                _ => chars[i] = ['(', ')', ',', '^', 'x', '.', '-', '\u{0}', '😀'][rng.below(9)],
            }
            let src: String = chars.into_iter().collect();
            if let Ok(e) = Expr::parse(&src) {
                let _ = e.eval(0.3, 0.1);
            }
        }
    }

    /// Speed of the reference expression; run with
    /// `cargo test --release -p memcontact --lib expr::tests::speed -- --ignored --nocapture`.
    #[test]
    #[ignore]
    fn speed() {
        let e = Expr::parse("0.5 + 0.1*sin(2*pi*x)*cos(2*pi*y)").unwrap();
        let n = 10_000_000;
        let start = std::time::Instant::now();
        let mut sum = 0.0;
        for i in 0..n {
            let t = i as f64 * 1e-7;
            sum += e.eval(std::hint::black_box(t), std::hint::black_box(1.0 - t));
        }
        let per = start.elapsed().as_secs_f64() / n as f64 * 1e9;
        let start = std::time::Instant::now();
        let mut sum2 = 0.0;
        for i in 0..n {
            let t = std::hint::black_box(i as f64 * 1e-7);
            let s = std::hint::black_box(1.0 - t);
            sum2 += 0.5 + 0.1 * (2.0 * PI * t).sin() * (2.0 * PI * s).cos();
        }
        let native = start.elapsed().as_secs_f64() / n as f64 * 1e9;
        let points: Vec<[f64; 2]> = (0..n)
            .map(|i| {
                let t = i as f64 * 1e-7;
                [t, 1.0 - t]
            })
            .collect();
        let mut values = vec![0.0; n];
        const CHUNK: usize = 7;
        let start = std::time::Instant::now();
        for (p, v) in points.chunks(CHUNK).zip(values.chunks_mut(CHUNK)) {
            e.eval_many(std::hint::black_box(p), v);
        }
        let many = start.elapsed().as_secs_f64() / n as f64 * 1e9;
        let sum3: f64 = values.iter().sum();
        println!(
            "expr: {per:.1} ns/eval, seven at once {many:.1} ns, native Rust: {native:.1} ns \
             ({sum} {sum2} {sum3})"
        );
        assert_eq!(sum, sum2);
        assert_eq!(sum, sum3);
    }
}
