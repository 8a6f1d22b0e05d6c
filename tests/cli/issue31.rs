//! Issue 31 (whole cities), item 6: every report says how far the bake is from its own ceiling
//! over the whole scene. `vocc eval --ceiling` adds the 2.5D ceiling of 10 ideal VOs
//! (`eval::bound::ceiling_sliced` with `CeilingParams::scene()`) for the evaluated cells, in the
//! text and the JSON report; without the flag the report has none.

use super::*;

#[test]
fn eval_ceiling_reports_the_whole_scene_ceiling_of_the_evaluated_cells() {
    let dir = common::temp_dir("cli-eval-ceiling");
    let (scene, store) = tiny_scene_and_store(&dir);
    let args = |extra: &[&'static str]| {
        let mut a = vec![
            "eval".to_string(),
            store.clone(),
            scene.clone(),
            "--height-attr".into(),
            "height".into(),
            "--cell".into(),
            "10,24".into(),
        ];
        a.extend(extra.iter().map(|s| s.to_string()));
        a
    };
    let json = |extra: &[&'static str]| -> serde_json::Value {
        let a = args(extra);
        let out = vocc(&a.iter().map(String::as_str).collect::<Vec<_>>());
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_slice(&out.stdout).unwrap()
    };
    let plain = json(&["--json"]);
    assert!(plain.get("ceiling").is_none(), "{plain}");
    let v = json(&["--json", "--ceiling"]);
    let c = &v["ceiling"];
    assert_eq!(c["cells"], 2, "{c}");
    assert_eq!(c["objects"], v["summary"]["objects"], "{c}");
    let share = c["occluded_share"].as_f64().unwrap();
    assert!((0.0..=1.0).contains(&share), "{c}");
    // The store's own figures are the same with or without the ceiling.
    assert_eq!(v["summary"]["mean_pvs"], plain["summary"]["mean_pvs"]);
    let a = args(&["--ceiling"]);
    let out = vocc(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("ceiling over the whole scene (10 ideal VOs in 2.5D, an estimate): "),
        "{text}"
    );
}
