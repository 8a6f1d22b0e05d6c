//! Text and JSON forms the commands' reports share.
//!
//! Input: counts and JSON values. Output: "1 cell" / "2 cells"; JSON with its timings rounded.
//! Invariant: presentation only; no figure changes but for the rounding of what is printed.

/// `n` and the noun, singular for 1: "1 cell", "2 cells".
pub fn plural(n: usize, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

/// Rounds the timings of a JSON report to what they mean (0.01 µs or ms, 0.001 s): the
/// fields whose names end in `_us`, `_ms` or `_s`, and `ms_per_cell_*`, at any depth, so
/// `15.780000000000001` prints as `15.78`.
pub fn round_timings(v: &mut serde_json::Value) {
    fn round(x: f64, digits: i32) -> f64 {
        let k = 10f64.powi(digits);
        let r = (x * k).round() / k;
        if r.is_finite() {
            r
        } else {
            x
        }
    }
    match v {
        serde_json::Value::Object(m) => {
            for (k, x) in m.iter_mut() {
                let digits = if k.ends_with("_us") || k.ends_with("_ms") || k.starts_with("ms_") {
                    Some(2)
                } else if k.ends_with("_s") {
                    Some(3)
                } else {
                    None
                };
                match (digits, x.as_f64()) {
                    (Some(d), Some(f)) if x.is_f64() => *x = round(f, d).into(),
                    _ => round_timings(x),
                }
            }
        }
        serde_json::Value::Array(a) => a.iter_mut().for_each(round_timings),
        _ => {}
    }
}
