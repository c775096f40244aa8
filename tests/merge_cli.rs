//! `aeroform merge` refuses an OUT that is one of its parts (issue 27, row 11): the part is
//! left as it was.

use crate::common;
use common::aeroform;

#[test]
fn merge_refuses_an_out_that_is_one_of_its_parts() {
    let dir = tempfile::tempdir().unwrap();
    let scen = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
    let spec = serde_json::json!({
        "kind": "flutter_map",
        "structure": scen.join("plate-rig.structure.toml"),
        "model": scen.join("plate-truth.model.toml"),
        "speeds": (0..30).map(|i| 1.0 + 0.5 * i as f64).collect::<Vec<_>>(),
        "grid": {"mu": [20.0, 30.0], "sigma": [0.4]},
    });
    let spec_path = dir.path().join("map.json");
    std::fs::write(&spec_path, spec.to_string()).unwrap();
    let s = |p: &std::path::Path| p.display().to_string();
    let parts: Vec<_> = (0..2)
        .map(|i| dir.path().join(format!("p{i}.json")))
        .collect();
    for (i, p) in parts.iter().enumerate() {
        let (ok, out, err) = aeroform(&[
            "sweep",
            &s(&spec_path),
            "--shard",
            &format!("{i}/2"),
            "--out",
            &s(p),
        ]);
        assert!(ok, "{out}\n{err}");
    }
    let before = std::fs::read(&parts[0]).unwrap();
    // the same file under another spelling of its path
    let alias = dir.path().join(".").join("p0.json");
    let (ok, _, err) = aeroform(&["merge", &s(&alias), &s(&parts[0]), &s(&parts[1])]);
    assert!(!ok);
    assert!(err.contains("also one of the parts"), "{err}");
    assert_eq!(std::fs::read(&parts[0]).unwrap(), before);
    // a new OUT works
    let merged = dir.path().join("merged.json");
    let (ok, out, err) = aeroform(&["merge", &s(&merged), &s(&parts[0]), &s(&parts[1])]);
    assert!(ok && merged.exists(), "{out}\n{err}");
}
