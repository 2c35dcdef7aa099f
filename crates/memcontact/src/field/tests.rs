//! Tests of fields: parsing, serde, binding to regions, checks.

use super::expr::Expr;
use super::value::number;
use super::*;
use crate::error::{Error, Result};
use std::collections::BTreeMap;
use std::f64::consts::PI;
use std::fmt;

fn names() -> BTreeMap<u32, String> {
    BTreeMap::from([(1, "soil".to_string()), (2, "foam".to_string())])
}

fn data_error(r: Result<impl fmt::Debug>) -> String {
    match r {
        Err(Error::Data(m)) => m,
        other => panic!("expected a data error, got {other:?}"),
    }
}

fn json(text: &str) -> Field {
    serde_json::from_str(text).unwrap_or_else(|e| panic!("{text}: {e}"))
}

#[test]
fn parse_numbers_and_expressions() {
    assert_eq!(Field::parse("3").unwrap(), Field::Constant(3.0));
    assert_eq!(Field::parse(" -2.5e-1 ").unwrap(), Field::Constant(-0.25));
    assert_eq!(Field::parse("2*pi").unwrap(), Field::Constant(2.0 * PI));
    assert_eq!(Field::from_number(4.5), Field::Constant(4.5));
    assert_eq!(Field::from(4.5), Field::Constant(4.5));
    match Field::parse("1 + x*y").unwrap() {
        Field::Expr(e) => assert_eq!(e.eval(2.0, 3.0), 7.0),
        other => panic!("{other:?}"),
    }
    assert!(matches!(Field::parse("1 + z"), Err(Error::Expr { .. })));
    assert!(matches!(Field::parse(""), Err(Error::Expr { .. })));
    assert!(matches!(Field::parse("inf"), Err(Error::Expr { .. })));
    assert_eq!(Field::parse("x").unwrap().constant(), None);
    assert_eq!(json(r#"{"a": 1, "b": "2/2"}"#).constant(), Some(1.0));
    assert_eq!(json(r#"{"a": 1, "b": 2}"#).constant(), None);
}

#[test]
fn uniform_fields_bind_to_any_mesh() {
    let c = Field::Constant(2.5)
        .bind("load f", &names(), &[1, 2])
        .unwrap();
    assert_eq!(c.name(), "load f");
    assert_eq!(c.eval([0.3, 0.4], 1), 2.5);
    assert_eq!(c.eval([0.3, 0.4], 99), 2.5);
    assert_eq!(c.constant(), Some(2.5));
    assert_eq!(c.region_constant(2), Some(2.5));

    let e = Field::parse("x^2 - y")
        .unwrap()
        .bind("obstacle φ", &BTreeMap::new(), &[0])
        .unwrap();
    assert_eq!(e.eval([3.0, 1.0], 0), 8.0);
    assert_eq!(e.eval([3.0, 1.0], 7), 8.0);
    assert_eq!(e.constant(), None);
    assert_eq!(e.region_constant(0), None);
}

#[test]
fn region_tables_by_name_tag_and_default() {
    let table = json(r#"{"soil": 100, "2": "50*x", "default": 7}"#);
    let h = table
        .bind("stiffness h", &names(), &[1, 2, 3, 2, 1])
        .unwrap();
    assert_eq!(h.eval([0.5, 0.0], 1), 100.0);
    assert_eq!(h.eval([0.5, 0.0], 2), 25.0);
    assert_eq!(h.eval([0.5, 0.0], 3), 7.0); // unnamed region 3: the default
    assert_eq!(h.eval([0.5, 0.0], 42), 7.0); // a region not bound: the default
    assert_eq!(h.constant(), None);
    assert_eq!(h.region_constant(1), Some(100.0));
    assert_eq!(h.region_constant(2), None);
    assert_eq!(h.region_constant(3), Some(7.0));

    // Without a default an unbound region is NaN, which the checks report.
    let h = json(r#"{"soil": 1, "foam": 2}"#)
        .bind("h", &names(), &[1, 2])
        .unwrap();
    assert!(h.eval([0.0, 0.0], 3).is_nan());
    assert_eq!(h.region_constant(3), None);
    assert_eq!(h.constant(), None);

    // The same constant on every region is a constant field.
    let h = json(r#"{"soil": 4, "default": "2*2"}"#)
        .bind("h", &names(), &[1, 2])
        .unwrap();
    assert_eq!(h.constant(), Some(4.0));
    // A constant expression counts as a constant.
    let h = Field::Regions(BTreeMap::from([(
        "soil".into(),
        Field::Expr(Expr::parse("3").unwrap()),
    )]))
    .bind("h", &names(), &[1])
    .unwrap();
    assert_eq!(h.region_constant(1), Some(3.0));
}

#[test]
fn binding_errors_name_the_field_and_the_regions() {
    let m = data_error(json(r#"{"clay": 1}"#).bind("stiffness", &names(), &[1, 2]));
    assert_eq!(
        m,
        "stiffness: no region named 'clay' in the mesh (regions: soil, foam)"
    );
    let m = data_error(json(r#"{"7": 1, "default": 0}"#).bind("h", &names(), &[1, 2, 3]));
    assert_eq!(
        m,
        "h: no region named '7' in the mesh (regions: soil, foam, 3)"
    );
    let m = data_error(json(r#"{"foam": 1}"#).bind("h", &names(), &[1]));
    assert!(m.contains("region 'foam' (tag 2) has no triangles"), "{m}");
    let m = data_error(json(r#"{"soil": 1}"#).bind("load f", &names(), &[1, 2]));
    assert_eq!(
        m,
        "load f: no value for region foam and no \"default\" entry (regions: soil, foam)"
    );
    // A name shared by two tags applies to both.
    let shared = BTreeMap::from([(1, "soil".to_string()), (5, "soil".to_string())]);
    let h = json(r#"{"soil": 3}"#).bind("h", &shared, &[1, 5]).unwrap();
    assert_eq!((h.eval([0.0, 0.0], 1), h.eval([0.0, 0.0], 5)), (3.0, 3.0));
    let m = data_error(json(r#"{"soil": 1, "1": 2}"#).bind("h", &names(), &[1, 2]));
    assert!(m.contains("region soil is given twice"), "{m}");
    let nested = Field::Regions(BTreeMap::from([(
        "soil".to_string(),
        Field::Regions(BTreeMap::from([("x".to_string(), Field::Constant(1.0))])),
    )]));
    let m = data_error(nested.bind("h", &names(), &[1]));
    assert!(m.contains("region 'soil' is a table"), "{m}");
    // The error displays as invalid data.
    let shown = json(r#"{"clay": 1}"#)
        .bind("h", &names(), &[1])
        .unwrap_err()
        .to_string();
    assert!(
        shown.starts_with("invalid data: h: no region named 'clay'"),
        "{shown}"
    );
}

#[test]
fn stiffness_rigid_or_elastic() {
    assert_eq!(Stiffness::parse("rigid").unwrap(), Stiffness::Rigid);
    assert_eq!(Stiffness::parse(" RiGiD ").unwrap(), Stiffness::Rigid);
    assert!(Stiffness::parse("rigid").unwrap().is_rigid());
    assert_eq!(
        Stiffness::parse("100").unwrap(),
        Stiffness::Elastic(Field::Constant(100.0))
    );
    assert_eq!(
        Stiffness::parse("1e3").unwrap().field(),
        Some(&Field::Constant(1000.0))
    );
    assert!(Stiffness::parse("rigidity").is_err());
    let s: Stiffness = serde_json::from_str("\"Rigid\"").unwrap();
    assert_eq!(s, Stiffness::Rigid);
    let s: Stiffness = serde_json::from_str("250").unwrap();
    assert_eq!(s, Stiffness::Elastic(Field::Constant(250.0)));
    let s: Stiffness = serde_json::from_str("\"100*(1+x)\"").unwrap();
    assert!(matches!(s, Stiffness::Elastic(Field::Expr(_))));
    let s: Stiffness = serde_json::from_str(r#"{"soil": 100, "foam": "50*x"}"#).unwrap();
    assert!(matches!(s, Stiffness::Elastic(Field::Regions(ref t)) if t.len() == 2));
    // A table may make some regions rigid (mixed bodies); other fields may not.
    let s: Stiffness = serde_json::from_str(r#"{"soil": "rigid", "foam": 50}"#).unwrap();
    let Stiffness::Mixed(t) = &s else {
        panic!("{s:?}")
    };
    assert_eq!(t["soil"], Stiffness::Rigid);
    assert_eq!(t["foam"], Stiffness::Elastic(Field::Constant(50.0)));
    let back = serde_json::to_string(&s).unwrap();
    assert_eq!(serde_json::from_str::<Stiffness>(&back).unwrap(), s);
    let e = serde_json::from_str::<Field>(r#"{"soil": "rigid"}"#)
        .unwrap_err()
        .to_string();
    assert!(e.contains("only the regions of a stiffness table"), "{e}");
}

#[test]
fn deserialise_from_json_values() {
    assert_eq!(json("3"), Field::Constant(3.0));
    assert_eq!(json("-3"), Field::Constant(-3.0));
    assert_eq!(json("2.5"), Field::Constant(2.5));
    assert_eq!(json("\"2.5\""), Field::Constant(2.5));
    assert_eq!(json("\"-pi\""), Field::Constant(-PI));
    match json("\"0.5 + 0.1*sin(2*pi*x)*cos(2*pi*y)\"") {
        Field::Expr(e) => assert!((e.eval(0.25, 0.0) - 0.6).abs() < 1e-15),
        other => panic!("{other:?}"),
    }
    match json(r#"{"soil": 100, "foam": "50*x", "default": "1/2"}"#) {
        Field::Regions(t) => {
            assert_eq!(t["soil"], Field::Constant(100.0));
            assert_eq!(t["default"], Field::Constant(0.5));
            assert!(matches!(t["foam"], Field::Expr(_)));
        }
        other => panic!("{other:?}"),
    }
    for (bad, fragment) in [
        ("true", "a number, a string"),
        ("[]", "empty array"),
        ("[1, \"x\"]", "f64"),
        ("null", "a number, a string"),
        ("\"1 + z\"", "unknown variable 'z'"),
        (r#"{"soil": {"a": 1}}"#, "a region's value"),
        (r#"{"soil": true}"#, "a region's value"),
        (r#"{"soil": "sin("}"#, "unexpected end of expression"),
        (r#"{"soil": 1, "soil": 2}"#, "given twice"),
        ("{}", "empty table"),
    ] {
        let e = serde_json::from_str::<Field>(bad).unwrap_err().to_string();
        assert!(e.contains(fragment), "{bad}: {e}");
    }
}

#[test]
fn serialise_round_trip() {
    for text in [r#"3.5"#, r#""x*y""#, r#"{"default":"1+x","soil":2.0}"#] {
        let f = json(text);
        let back = serde_json::to_string(&f).unwrap();
        assert_eq!(json(&back), f, "{text} -> {back}");
    }
    assert_eq!(
        serde_json::to_string(&Stiffness::Rigid).unwrap(),
        "\"rigid\""
    );
}

#[test]
fn checks_report_value_and_place() {
    let pts = [
        ([0.0, 0.0], 1.0),
        ([0.25, 0.5], -3.0),
        ([1.0, 1.0], -1.0),
        ([2.0, 0.0], 0.0),
    ];
    let m = data_error(check_values("stiffness h", pts, Rule::FiniteNonNegative));
    assert_eq!(
        m,
        "stiffness h is negative (-3) at (0.25, 0.5) (and at 1 more point)"
    );
    assert!(check_values("load f", pts, Rule::Finite).is_ok());
    let m = data_error(check_values("t", pts, Rule::FinitePositive));
    assert_eq!(
        m,
        "t is not positive (-3) at (0.25, 0.5) (and at 2 more points)"
    );
    assert!(check_values("h", [([0.0, 0.0], 0.0)], Rule::FiniteNonNegative).is_ok());
    assert!(check_values("h", std::iter::empty(), Rule::FinitePositive).is_ok());
    for rule in [Rule::Finite, Rule::FiniteNonNegative, Rule::FinitePositive] {
        let m = data_error(check_values("f", [([1.0, 2.0], f64::NAN)], rule));
        assert_eq!(m, "f is not a number (NaN) at (1, 2)");
        let m = data_error(check_values("f", [([1.0, 2.0], f64::INFINITY)], rule));
        assert_eq!(m, "f is infinite (inf) at (1, 2)");
        let m = data_error(check_values("f", [([1.0, 2.0], f64::NEG_INFINITY)], rule));
        assert_eq!(m, "f is infinite (-inf) at (1, 2)");
    }
    let m = data_error(check_value("tension t", 0.0, Rule::FinitePositive));
    assert_eq!(m, "tension t is not positive (0)");
    assert!(check_value("tension t", 1e-12, Rule::FinitePositive).is_ok());
    let shown = check_value("t", -1.0, Rule::FinitePositive)
        .unwrap_err()
        .to_string();
    assert_eq!(shown, "invalid data: t is not positive (-1)");
    // Long numbers are shortened to 6 significant digits.
    let m = data_error(check_values(
        "h",
        [([0.1 + 0.2, 1.0 / 3.0], -1e-9)],
        Rule::FiniteNonNegative,
    ));
    assert_eq!(m, "h is negative (-1e-9) at (0.3, 0.333333)");
    assert_eq!(number(1234567.0), "1.23457e6");
    assert_eq!(number(-2.5e20), "-2.5e20");
    assert_eq!(number(100.0), "100");
    assert_eq!(number(0.000123456789), "0.000123457");
}

#[test]
fn thread_safe() {
    fn check<T: Send + Sync>() {}
    check::<Field>();
    check::<BoundField>();
    check::<Stiffness>();
}

#[test]
fn ambiguous_region_names_are_refused() {
    // Tag 5 is named "2", and tag 2 exists: the key "2" could mean either.
    let names = BTreeMap::from([
        (2, "clay".to_string()),
        (5, "2".to_string()),
        (6, "default".to_string()),
        (7, String::new()),
        (8, "8".to_string()),
    ]);
    let tags = [2, 5, 6, 7, 8, 2];
    let m = data_error(json(r#"{"2": 1, "default": 0}"#).bind("stiffness h", &names, &tags));
    assert!(m.contains("'2' is ambiguous") && m.contains("clay"), "{m}");
    // Tags reach the regions whose names are reserved or empty; a name equal to its
    // own tag is no ambiguity.
    let h = json(r#"{"6": 1, "7": 2, "8": 3, "clay": 4, "default": 0}"#)
        .bind("stiffness h", &names, &tags)
        .unwrap();
    assert_eq!(h.eval([0.0, 0.0], 6), 1.0);
    assert_eq!(h.eval([0.0, 0.0], 7), 2.0);
    assert_eq!(h.eval([0.0, 0.0], 8), 3.0);
    assert_eq!(h.eval([0.0, 0.0], 5), 0.0);
}
