//! Attribute values as numbers: heights written the way real files write them.
//!
//! Input: one attribute value of a GeoJSON feature (JSON number, string, or anything else).
//! Output: [`Value::Number`], [`Value::Missing`] (absent, `null`, empty string) or
//! [`Value::Bad`] (present, but its meaning is not clear), for a length ([`metres`]) or a count
//! ([`count`]).
//! Rules, for strings (the meaning must be clear, otherwise the value is bad):
//! - surrounding spaces are ignored; an empty string is missing;
//! - a length may end in a unit, with or without a space, in any case: `m`, `meter(s)`,
//!   `metre(s)` (metres), or `ft`, `feet`, `foot` (international feet, 0.3048 m);
//! - one decimal separator, a point or a comma (`12.13`, `12,5`); a comma followed by exactly
//!   three digits (`1,234`) could be a thousands separator and is bad, and so is a number with
//!   both a point and a comma;
//! - the number itself is what Rust's `f64` parser accepts for decimal text (sign, digits,
//!   exponent), and must be finite; counts take no unit.
//!
//! Invariant: never panics; every accepted string has one reading.

use serde_json::Value as Json;

/// An attribute value read as a number.
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    Number(f64),
    /// Absent, `null` or an empty string.
    Missing,
    /// Present but not a number whose meaning is clear; the value as written in the file.
    Bad(String),
}

/// Feet to metres (the international foot).
pub const FOOT_M: f64 = 0.3048;

/// A length in metres (a height or a base elevation). See the module header.
pub fn metres(v: Option<&Json>) -> Value {
    read(v, true)
}

/// A count (storeys). See the module header; no unit is accepted.
pub fn count(v: Option<&Json>) -> Value {
    read(v, false)
}

fn read(v: Option<&Json>, length: bool) -> Value {
    match v {
        None | Some(Json::Null) => Value::Missing,
        Some(Json::Number(n)) => match n.as_f64() {
            Some(f) if f.is_finite() => Value::Number(f),
            _ => Value::Bad(n.to_string()),
        },
        Some(Json::String(s)) => {
            if s.trim().is_empty() {
                Value::Missing
            } else {
                match parse(s, length) {
                    Some(f) => Value::Number(f),
                    None => Value::Bad(format!("{s:?}")),
                }
            }
        }
        Some(other) => Value::Bad(other.to_string()),
    }
}

/// Parses a string by the module's rules: a length (`length`, units allowed) or a count.
pub fn parse(s: &str, length: bool) -> Option<f64> {
    let t = s.trim();
    let (num, factor) = if length { split_unit(t)? } else { (t, 1.0) };
    let num = num.trim_end();
    if num.is_empty()
        || !num
            .bytes()
            .all(|b| b.is_ascii_digit() || b"+-.,eE".contains(&b))
    {
        return None;
    }
    let commas = num.matches(',').count();
    let text = match (commas, num.contains('.')) {
        (0, _) => num.to_string(),
        (1, false) => {
            let after = &num[num.find(',')? + 1..];
            let digits = after.bytes().take_while(u8::is_ascii_digit).count();
            if digits == 3 || digits == 0 {
                return None;
            }
            num.replacen(',', ".", 1)
        }
        _ => return None,
    };
    let f: f64 = text.parse().ok()?;
    let v = f * factor;
    v.is_finite().then_some(v)
}

/// The number part and the factor to metres of a length with an optional unit suffix.
fn split_unit(t: &str) -> Option<(&str, f64)> {
    let lower = t.to_ascii_lowercase();
    // Longest names first, so "meters" is not read as "meter" + "s".
    const UNITS: [(&str, f64); 8] = [
        ("meters", 1.0),
        ("metres", 1.0),
        ("meter", 1.0),
        ("metre", 1.0),
        ("feet", FOOT_M),
        ("foot", FOOT_M),
        ("ft", FOOT_M),
        ("m", 1.0),
    ];
    for (u, f) in UNITS {
        if let Some(rest) = lower.strip_suffix(u) {
            // The unit must follow the number (or a space), not end a word like "5em".
            if rest
                .bytes()
                .last()
                .is_some_and(|b| b.is_ascii_digit() || b == b' ' || b == b'.')
            {
                return Some((&t[..rest.len()], f));
            }
            return None;
        }
    }
    Some((t, 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn lengths_with_units_and_decimal_commas() {
        let ok = |s: &str, want: f64| {
            let got = parse(s, true).unwrap_or_else(|| panic!("{s:?} did not parse"));
            assert!((got - want).abs() < 1e-12, "{s:?}: {got}");
        };
        ok("12.13", 12.13);
        ok("12.13 m", 12.13);
        ok("12.13m", 12.13);
        ok(" 12.13 M ", 12.13);
        ok("12,5", 12.5);
        ok("12,5 m", 12.5);
        ok("7 metres", 7.0);
        ok("7 meters", 7.0);
        ok("7 meter", 7.0);
        ok("40 ft", 40.0 * FOOT_M);
        ok("40ft", 40.0 * FOOT_M);
        ok("10 feet", 10.0 * FOOT_M);
        ok("1e1", 10.0);
        ok("-3", -3.0);
        ok("12.", 12.0);
        for bad in [
            "1,234",
            "1,234.5",
            "1.234,5",
            "12,",
            "abc",
            "12 m tall",
            "12 yards",
            "m",
            "5em",
            "12..5",
            "1,2,3",
            "inf",
            "NaN",
            "12 m m",
            "-",
        ] {
            assert_eq!(parse(bad, true), None, "{bad:?}");
        }
        // Counts take no unit.
        assert_eq!(parse("3", false), Some(3.0));
        assert_eq!(parse("2,5", false), Some(2.5));
        assert_eq!(parse("3 m", false), None);
    }

    #[test]
    fn json_values() {
        assert_eq!(metres(None), Value::Missing);
        assert_eq!(metres(Some(&json!(null))), Value::Missing);
        assert_eq!(metres(Some(&json!("  "))), Value::Missing);
        assert_eq!(metres(Some(&json!(12.5))), Value::Number(12.5));
        assert_eq!(metres(Some(&json!("12.13 m"))), Value::Number(12.13));
        assert_eq!(metres(Some(&json!("tall"))), Value::Bad("\"tall\"".into()));
        assert_eq!(metres(Some(&json!(true))), Value::Bad("true".into()));
        assert_eq!(metres(Some(&json!([1]))), Value::Bad("[1]".into()));
        assert_eq!(count(Some(&json!("4"))), Value::Number(4.0));
    }
}
