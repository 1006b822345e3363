//! A recursive-descent parser of Python's expression grammar, the part xacro files use:
//! `a if c else b`, `or`, `and`, `not`, chained comparisons (`< <= > >= == != in not in is`),
//! `+ -`, `* / // %`, unary `- + ~`, `**`, calls with keyword arguments, subscripts, attribute
//! access, and list / tuple / dict displays. Lambdas, comprehensions and slices are refused as
//! unsupported (the caller may fall back to Python's xacro).

use super::lex::Token;
use super::ExprError;
use crate::value::Value;

/// Nesting beyond this many brackets or operators is refused (a guard for the stack).
const MAX_DEPTH: usize = 100;

/// An expression.
#[derive(Clone, Debug)]
pub enum Expr {
    /// A literal.
    Lit(Value),
    /// A name.
    Name(String),
    /// `[a, b]` or `(a, b)`.
    List(Vec<Expr>),
    /// `{k: v}`.
    Dict(Vec<(Expr, Expr)>),
    /// A unary operator: `-`, `+`, `~` or `not`.
    Unary(&'static str, Box<Expr>),
    /// An arithmetic operator.
    Bin(&'static str, Box<Expr>, Box<Expr>),
    /// A chain of comparisons `a < b <= c`.
    Cmp(Box<Expr>, Vec<(&'static str, Expr)>),
    /// `a and b`.
    And(Box<Expr>, Box<Expr>),
    /// `a or b`.
    Or(Box<Expr>, Box<Expr>),
    /// `then if cond else other`.
    IfElse(Box<Expr>, Box<Expr>, Box<Expr>),
    /// A call with positional and keyword arguments.
    Call(Box<Expr>, Vec<Expr>, Vec<(String, Expr)>),
    /// `a[b]`.
    Index(Box<Expr>, Box<Expr>),
    /// `a.name`.
    Attr(Box<Expr>, String),
}

/// Parses the tokens of one expression.
///
/// # Errors
/// A syntax error, or a construct this evaluator does not support.
pub fn parse(tokens: &[Token]) -> Result<Expr, ExprError> {
    let mut p = Parser {
        tokens,
        at: 0,
        depth: 0,
    };
    let e = p.expr()?;
    match p.peek() {
        None => Ok(e),
        Some(t) => Err(ExprError::new(format!(
            "expected the end of the expression, found {}",
            show(t)
        ))),
    }
}

fn show(t: &Token) -> String {
    match t {
        Token::Num(v) => v.repr(),
        Token::Str(s) => format!("'{s}'"),
        Token::Name(n) => format!("'{n}'"),
        Token::Op(o) => format!("'{o}'"),
    }
}

/// A call's positional and keyword arguments.
type Arguments = (Vec<Expr>, Vec<(String, Expr)>);

struct Parser<'a> {
    tokens: &'a [Token],
    at: usize,
    depth: usize,
}

impl Parser<'_> {
    fn peek(&self) -> Option<&Token> {
        self.tokens.get(self.at)
    }

    fn is_op(&self, op: &str) -> bool {
        matches!(self.peek(), Some(Token::Op(o)) if *o == op)
    }

    fn is_word(&self, word: &str) -> bool {
        matches!(self.peek(), Some(Token::Name(n)) if n == word)
    }

    fn eat_op(&mut self, op: &str) -> bool {
        let yes = self.is_op(op);
        if yes {
            self.at += 1;
        }
        yes
    }

    fn eat_word(&mut self, word: &str) -> bool {
        let yes = self.is_word(word);
        if yes {
            self.at += 1;
        }
        yes
    }

    fn expect_op(&mut self, op: &str) -> Result<(), ExprError> {
        if self.eat_op(op) {
            return Ok(());
        }
        Err(ExprError::new(match self.peek() {
            Some(t) => format!("expected '{op}', found {}", show(t)),
            None => format!("expected '{op}', found the end of the expression"),
        }))
    }

    fn nest(&mut self) -> Result<(), ExprError> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(ExprError::new(format!(
                "expression nested deeper than {MAX_DEPTH} levels"
            )));
        }
        Ok(())
    }

    fn expr(&mut self) -> Result<Expr, ExprError> {
        self.nest()?;
        if self.is_word("lambda") {
            return Err(ExprError::unsupported("lambda expressions"));
        }
        let then = self.or()?;
        let e = if self.eat_word("if") {
            let cond = self.or()?;
            if !self.eat_word("else") {
                return Err(ExprError::new(
                    "expected 'else' in a conditional expression",
                ));
            }
            let other = self.expr()?;
            Expr::IfElse(Box::new(then), Box::new(cond), Box::new(other))
        } else {
            then
        };
        self.depth -= 1;
        Ok(e)
    }

    fn or(&mut self) -> Result<Expr, ExprError> {
        let mut e = self.and()?;
        while self.eat_word("or") {
            e = Expr::Or(Box::new(e), Box::new(self.and()?));
        }
        Ok(e)
    }

    fn and(&mut self) -> Result<Expr, ExprError> {
        let mut e = self.not()?;
        while self.eat_word("and") {
            e = Expr::And(Box::new(e), Box::new(self.not()?));
        }
        Ok(e)
    }

    fn not(&mut self) -> Result<Expr, ExprError> {
        if self.eat_word("not") {
            self.nest()?;
            let e = Expr::Unary("not", Box::new(self.not()?));
            self.depth -= 1;
            return Ok(e);
        }
        self.comparison()
    }

    fn comparison(&mut self) -> Result<Expr, ExprError> {
        let first = self.arith()?;
        let mut rest = Vec::new();
        loop {
            let op =
                if let Some(Token::Op(o @ ("<" | ">" | "==" | "!=" | "<=" | ">="))) = self.peek() {
                    let o = *o;
                    self.at += 1;
                    o
                } else if self.eat_word("in") {
                    "in"
                } else if self.is_word("not")
                    && matches!(self.tokens.get(self.at + 1), Some(Token::Name(n)) if n == "in")
                {
                    self.at += 2;
                    "not in"
                } else if self.eat_word("is") {
                    if self.eat_word("not") {
                        "is not"
                    } else {
                        "is"
                    }
                } else {
                    break;
                };
            rest.push((op, self.arith()?));
        }
        Ok(if rest.is_empty() {
            first
        } else {
            Expr::Cmp(Box::new(first), rest)
        })
    }

    fn arith(&mut self) -> Result<Expr, ExprError> {
        let mut e = self.term()?;
        loop {
            let op = if self.eat_op("+") {
                "+"
            } else if self.eat_op("-") {
                "-"
            } else {
                return Ok(e);
            };
            e = Expr::Bin(op, Box::new(e), Box::new(self.term()?));
        }
    }

    fn term(&mut self) -> Result<Expr, ExprError> {
        let mut e = self.factor()?;
        loop {
            let op = match self.peek() {
                Some(Token::Op(o @ ("*" | "/" | "//" | "%"))) => *o,
                _ => return Ok(e),
            };
            self.at += 1;
            e = Expr::Bin(op, Box::new(e), Box::new(self.factor()?));
        }
    }

    fn factor(&mut self) -> Result<Expr, ExprError> {
        if let Some(Token::Op(o @ ("-" | "+" | "~"))) = self.peek() {
            let o = *o;
            self.at += 1;
            self.nest()?;
            let e = Expr::Unary(o, Box::new(self.factor()?));
            self.depth -= 1;
            return Ok(e);
        }
        let base = self.primary()?;
        if self.eat_op("**") {
            self.nest()?;
            let exp = self.factor()?;
            self.depth -= 1;
            return Ok(Expr::Bin("**", Box::new(base), Box::new(exp)));
        }
        Ok(base)
    }

    fn primary(&mut self) -> Result<Expr, ExprError> {
        let mut e = self.atom()?;
        loop {
            if self.eat_op("(") {
                let (args, kwargs) = self.arguments()?;
                e = Expr::Call(Box::new(e), args, kwargs);
            } else if self.eat_op("[") {
                let index = self.expr()?;
                if self.is_op(":") {
                    return Err(ExprError::unsupported("slices"));
                }
                self.expect_op("]")?;
                e = Expr::Index(Box::new(e), Box::new(index));
            } else if self.eat_op(".") {
                match self.tokens.get(self.at) {
                    Some(Token::Name(n)) => {
                        e = Expr::Attr(Box::new(e), n.clone());
                        self.at += 1;
                    }
                    _ => return Err(ExprError::new("expected a name after '.'")),
                }
            } else {
                return Ok(e);
            }
        }
    }

    fn arguments(&mut self) -> Result<Arguments, ExprError> {
        let mut args = Vec::new();
        let mut kwargs = Vec::new();
        while !self.eat_op(")") {
            let keyword = match (self.peek(), self.tokens.get(self.at + 1)) {
                (Some(Token::Name(n)), Some(Token::Op("="))) => Some(n.clone()),
                _ => None,
            };
            if let Some(k) = keyword {
                self.at += 2;
                kwargs.push((k, self.expr()?));
            } else if self.is_op("*") || self.is_op("**") {
                return Err(ExprError::unsupported("argument unpacking (* and **)"));
            } else {
                args.push(self.expr()?);
            }
            if self.is_word("for") {
                return Err(ExprError::unsupported("generator expressions"));
            }
            if !self.eat_op(",") {
                self.expect_op(")")?;
                break;
            }
        }
        Ok((args, kwargs))
    }

    /// Items up to `close`, comma-separated; whether a comma was seen (a tuple).
    fn items(&mut self, close: &str) -> Result<(Vec<Expr>, bool), ExprError> {
        let mut items = Vec::new();
        let mut comma = false;
        while !self.eat_op(close) {
            items.push(self.expr()?);
            if self.is_word("for") {
                return Err(ExprError::unsupported("comprehensions"));
            }
            if self.eat_op(",") {
                comma = true;
            } else {
                self.expect_op(close)?;
                break;
            }
        }
        Ok((items, comma))
    }

    fn atom(&mut self) -> Result<Expr, ExprError> {
        let Some(token) = self.peek().cloned() else {
            return Err(ExprError::new(
                "expected a value, found the end of the expression",
            ));
        };
        self.at += 1;
        match token {
            Token::Num(v) => Ok(Expr::Lit(v)),
            Token::Str(mut s) => {
                while let Some(Token::Str(more)) = self.peek() {
                    s.push_str(more);
                    self.at += 1;
                }
                Ok(Expr::Lit(Value::str(s)))
            }
            Token::Name(n) => Ok(match n.as_str() {
                "True" => Expr::Lit(Value::Bool(true)),
                "False" => Expr::Lit(Value::Bool(false)),
                "None" => Expr::Lit(Value::None),
                "lambda" | "for" | "if" | "else" | "and" | "or" | "not" | "in" | "is" => {
                    return Err(ExprError::new(format!("expected a value, found '{n}'")))
                }
                _ => Expr::Name(n),
            }),
            Token::Op("(") => {
                self.nest()?;
                let (items, comma) = self.items(")")?;
                self.depth -= 1;
                Ok(match (items.len(), comma) {
                    (1, false) => items.into_iter().next().unwrap_or(Expr::Lit(Value::None)),
                    _ => Expr::List(items),
                })
            }
            Token::Op("[") => {
                self.nest()?;
                let (items, _) = self.items("]")?;
                self.depth -= 1;
                Ok(Expr::List(items))
            }
            Token::Op("{") => {
                self.nest()?;
                let mut pairs = Vec::new();
                while !self.eat_op("}") {
                    let k = self.expr()?;
                    if !self.eat_op(":") {
                        return Err(ExprError::unsupported("set displays"));
                    }
                    let v = self.expr()?;
                    pairs.push((k, v));
                    if !self.eat_op(",") {
                        self.expect_op("}")?;
                        break;
                    }
                }
                self.depth -= 1;
                Ok(Expr::Dict(pairs))
            }
            other => Err(ExprError::new(format!(
                "expected a value, found {}",
                show(&other)
            ))),
        }
    }
}
