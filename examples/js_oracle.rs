//! The Rust decoder's answers for the JavaScript runtime's tests (`js/test/`): what
//! `Store::parse` and `decode_blob` say of each file, and the bits of `f64::hypot`.
//!
//! Input: `store FILE...` or `blob FILE...` (a blob file as the fuzz target `blob` reads it:
//! with at least 112 bytes, a frame then the blob; shorter, the blob alone with
//! `vocc::fuzzing::BLOB_FRAME`), or `hypot` with pairs of `f64` bit patterns (16 hex digits
//! each) on standard input, one pair a line.
//! Output: one JSON line per file, `{"file", "ok", "error"}` (the error's `Display`) and, for an
//! accepted input, the records of every cell (`[skipped, ground, rise, [[ae, ax, ay, be, bx,
//! by, level, deep], ...]]`, the rise and deep flags of format 2.1), the version and the scene
//! section; for `hypot`, one bit pattern a line.
//! Invariant: only the library's public decoders are called.

use std::io::BufRead;
use std::process::ExitCode;

use serde_json::json;
use vocc::runtime::format::{decode_blob, decode_frame, CellRecord, FormatError, Store, FRAME_LEN};

fn record_json(rec: &CellRecord) -> serde_json::Value {
    let vos: Vec<serde_json::Value> = rec
        .vos()
        .iter()
        .map(|q| json!([q.a.e, q.a.x, q.a.y, q.b.e, q.b.x, q.b.y, q.level, q.deep]))
        .collect();
    json!([
        matches!(rec, CellRecord::Skipped),
        rec.ground(),
        rec.rise(),
        vos
    ])
}

fn store(bytes: &[u8]) -> Result<serde_json::Value, FormatError> {
    let s = Store::parse(bytes)?;
    let mut cells = Vec::new();
    for id in 0..s.cell_count() {
        cells.push(record_json(&s.cell(id)?));
    }
    Ok(json!({
        "version": [s.version().0, s.version().1],
        "objects": s.objects(),
        "scene": format!("{:016x}", s.scene()),
        "crs": s.crs(),
        "cells": cells,
    }))
}

fn blob(bytes: &[u8]) -> Result<serde_json::Value, FormatError> {
    let (frame, rest) = match bytes.split_first_chunk::<FRAME_LEN>() {
        Some((head, rest)) => (decode_frame(head)?, rest),
        None => (vocc::fuzzing::BLOB_FRAME, bytes),
    };
    let (id, rec) = decode_blob(&frame, rest)?;
    Ok(json!({"id": id, "record": record_json(&rec)}))
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(mode) = args.first() else {
        eprintln!("usage: js_oracle (store|blob) FILE... | js_oracle hypot < PAIRS");
        return ExitCode::from(2);
    };
    if mode == "hypot" {
        for line in std::io::stdin().lock().lines() {
            let line = line.expect("read stdin");
            let v: Vec<u64> = line
                .split_whitespace()
                .map(|t| u64::from_str_radix(t, 16).expect("hex bits"))
                .collect();
            let h = f64::from_bits(v[0]).hypot(f64::from_bits(v[1]));
            println!("{:016x}", h.to_bits());
        }
        return ExitCode::SUCCESS;
    }
    let decode: fn(&[u8]) -> Result<serde_json::Value, FormatError> = match mode.as_str() {
        "store" => store,
        "blob" => blob,
        _ => {
            eprintln!("unknown mode {mode}");
            return ExitCode::from(2);
        }
    };
    for file in &args[1..] {
        let bytes = std::fs::read(file).expect("read a file");
        let line = match decode(&bytes) {
            Ok(v) => json!({"file": file, "ok": true, "value": v}),
            Err(e) => json!({"file": file, "ok": false, "error": e.to_string()}),
        };
        println!("{line}");
    }
    ExitCode::SUCCESS
}
