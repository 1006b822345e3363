//! The `${}` evaluator alone: Python's results for the expressions real xacro files use, and
//! its errors.

use std::rc::Rc;

use urdf_xacro::expr::{evaluate, ExprError, Names};
use urdf_xacro::value::Value;

/// Names `a` = 3, `half` = 0.5, `name` = 'arm', `q` = [1, 2.5], `d` = {'j1': 0.25}.
struct Fixture;

impl Names for Fixture {
    fn lookup(&mut self, name: &str) -> Result<Option<Value>, ExprError> {
        Ok(match name {
            "a" => Some(Value::Int(3)),
            "half" => Some(Value::Float(0.5)),
            "name" => Some(Value::str("arm")),
            "q" => Some(Value::List(Rc::new(vec![Value::Int(1), Value::Float(2.5)]))),
            "d" => Some(Value::Dict(Rc::new(vec![(
                Value::str("j1"),
                Value::Float(0.25),
            )]))),
            _ => None,
        })
    }
    fn call(&mut self, _: &str, _: &[Value]) -> Result<Option<Value>, ExprError> {
        Ok(None)
    }
}

fn text(src: &str) -> String {
    evaluate(src, &mut Fixture)
        .unwrap_or_else(|e| panic!("{src}: {}", e.message))
        .to_text()
}

fn error(src: &str) -> ExprError {
    match evaluate(src, &mut Fixture) {
        Ok(v) => panic!("{src}: expected an error, found {}", v.repr()),
        Err(e) => e,
    }
}

#[test]
fn arithmetic_follows_python() {
    let cases = [
        ("1 + 2 * 3", "7"),
        ("13/3 * 250.532/17.19", "63.15524529765367"),
        ("4/2", "2.0"),
        ("7 // 2", "3"),
        ("-7 // 2", "-4"),
        ("7 % -2", "-1"),
        ("2 ** 10", "1024"),
        ("2 ** -1", "0.5"),
        ("-2 ** 2", "-4"),
        ("(729.0/25.0)*(22.0/16.0)", "40.095"),
        ("a * half", "1.5"),
        ("0.018 + 2.9433464e-02", "0.047433463999999995"),
        ("1e-5", "1e-05"),
        ("True + 1", "2"),
    ];
    for (src, want) in cases {
        assert_eq!(text(src), want, "{src}");
    }
}

#[test]
fn math_names_and_functions() {
    let cases = [
        ("pi", "3.141592653589793"),
        ("-pi/2", "-1.5707963267948966"),
        ("radians(180)", "3.141592653589793"),
        ("radians( 90)", "1.5707963267948966"),
        ("degrees(pi)", "180.0"),
        ("sqrt(16)", "4.0"),
        ("math.cos(0)", "1.0"),
        ("atan2(1, 1) * 4", "3.141592653589793"),
        ("floor(2.7)", "2"),
        ("abs(-3)", "3"),
        ("max(1, 4, 2)", "4"),
        ("min(q)", "1"),
        ("round(2.5)", "2"),
        ("round(2.675, 2)", "2.67"),
        ("round(0.125, 2)", "0.12"),
        ("int('7') + float('0.5')", "7.5"),
        ("len(name)", "3"),
    ];
    for (src, want) in cases {
        assert_eq!(text(src), want, "{src}");
    }
}

#[test]
fn logic_comparisons_and_conditionals() {
    let cases = [
        ("a == 3", "True"),
        ("name == 'arm'", "True"),
        ("name != ''", "True"),
        ("1 < a <= 3", "True"),
        ("1 < a < 3", "False"),
        ("not a", "False"),
        ("a and 'x'", "x"),
        ("0 or half", "0.5"),
        ("'big' if a > 2 else 'small'", "big"),
        ("'big' if a > 5 else 'small'", "small"),
        ("'r' in name", "True"),
        ("5 not in q", "True"),
        ("None is None", "True"),
    ];
    for (src, want) in cases {
        assert_eq!(text(src), want, "{src}");
    }
}

#[test]
fn strings_lists_and_dicts() {
    let cases = [
        ("name + '_link'", "arm_link"),
        ("'a' 'b'", "ab"),
        ("q[1]", "2.5"),
        ("q[-1]", "2.5"),
        ("d['j1']", "0.25"),
        ("d.j1", "0.25"),
        ("dict(joint_1=0.0, joint_2=1)['joint_2']", "1"),
        ("[1, 2] + [3]", "[1, 2, 3]"),
        ("{'a': 1}['a']", "1"),
        ("str(half) + 'm'", "0.5m"),
        ("'-' * 3", "---"),
    ];
    for (src, want) in cases {
        assert_eq!(text(src), want, "{src}");
    }
}

#[test]
fn errors_say_what_is_wrong() {
    assert!(error("b + 1").message.contains("undefined name 'b'"));
    assert!(error("1/0").message.contains("division by zero"));
    assert!(error("a // 0").message.contains("division by zero"));
    assert!(error("1.0 % 0").message.contains("division by zero"));
    assert!(error("sqrt(-1)").message.contains("math domain error"));
    assert!(error("name * half").message.contains("expected a number"));
    assert!(error("q[5]").message.contains("out of range"));
    assert!(error("d['j9']").message.contains("not found"));
    assert!(error("(1 + 2").message.contains("expected ')'"));
    assert!(error("1 +").message.contains("expected a value"));
    assert!(error("2 ** 100").message.contains("overflow"));
    assert!(error("'ab").message.contains("unterminated string"));
    assert!(error("a if a").message.contains("expected 'else'"));
}

#[test]
fn unsupported_constructs_are_named() {
    for (src, construct) in [
        ("lambda x: x", "lambda expressions"),
        ("[x for x in q]", "comprehensions"),
        ("q[0:1]", "slices"),
        ("'%d' % a", "string formatting with %"),
        (
            "xacro.warning('x')",
            "xacro's message, tokenize and abs_filename functions",
        ),
    ] {
        assert_eq!(error(src).unsupported.as_deref(), Some(construct), "{src}");
    }
    // Not unsupported, just wrong.
    assert_eq!(error("b").unsupported, None);
}

#[test]
fn deep_nesting_is_refused_not_overflowed() {
    let src = format!("{}1{}", "(".repeat(5000), ")".repeat(5000));
    assert!(error(&src).message.contains("nested deeper"));
    let src = format!("{}1", "-".repeat(5000));
    assert!(error(&src).message.contains("nested deeper"));
}

#[test]
fn huge_values_are_refused() {
    assert!(error("'a' * 10 ** 9").message.contains("exceeds the limit"));
    assert!(error("range(10 ** 9)")
        .message
        .contains("exceeds the limit"));
}
