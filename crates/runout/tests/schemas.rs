//! docs/schema/*.json are what schemars generates from the report types (regenerate with
//! `RUNOUT_UPDATE_SCHEMAS=1 cargo test -p runout --test schemas`), and every JSON output of the
//! CLI snapshot tests (crates/runout-cli/tests/cli/snapshots, the CLI's stdout byte for byte)
//! validates against the schema its `schema` field names.

use std::collections::BTreeMap;
use std::path::PathBuf;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

#[test]
fn published_schemas_are_up_to_date() {
    let dir = root().join("docs/schema");
    let update = std::env::var_os("RUNOUT_UPDATE_SCHEMAS").is_some();
    for (id, file, text) in runout::schema::all() {
        let p = dir.join(&file);
        if update {
            std::fs::write(&p, &text).unwrap();
            continue;
        }
        let published = std::fs::read_to_string(&p).unwrap_or_else(|e| {
            panic!("{}: {e} (regenerate: RUNOUT_UPDATE_SCHEMAS=1)", p.display())
        });
        assert!(
            published == text,
            "{} is stale for {id}: regenerate with RUNOUT_UPDATE_SCHEMAS=1 cargo test -p runout --test schemas",
            p.display()
        );
        let v: serde_json::Value = serde_json::from_str(&published).unwrap();
        assert!(v["properties"]["schema"].is_object(), "{file}");
    }
}

/// The JSON body of an insta snapshot file.
fn snapshot_body(text: &str) -> &str {
    let rest = text.strip_prefix("---").expect("snapshot header");
    let end = rest.find("\n---\n").expect("end of header");
    &rest[end + 5..]
}

/// The snapshot of `chip compare` has its wall-clock throughput redacted to a string: put a
/// throughput of the documented shape back (the numbers are checked by the snapshot); likewise
/// the batch report's wall-clock `elapsed_s` and `recordings_per_s` (`"[wall-clock]"`).
fn unredact(v: &mut serde_json::Value, top: bool) {
    match v {
        serde_json::Value::Object(m) => {
            for (k, x) in m.iter_mut() {
                if x == "[wall-clock]" {
                    *x = 1.5.into();
                } else if k == "throughput_points_per_s" && x == "[throughput]" {
                    let mut t = serde_json::Map::new();
                    for model in ["exact", "equivalent", "arc"] {
                        t.insert(model.into(), 1.0.into());
                    }
                    if top {
                        t.insert("note".into(), "redacted".into());
                    }
                    *x = t.into();
                } else {
                    unredact(x, false);
                }
            }
        }
        serde_json::Value::Array(a) => a.iter_mut().for_each(|x| unredact(x, false)),
        _ => {}
    }
}

#[test]
fn cli_outputs_validate_against_their_schemas() {
    let schemas: BTreeMap<&str, jsonschema::Validator> = runout::schema::all()
        .into_iter()
        .map(|(id, _, text)| {
            let s: serde_json::Value = serde_json::from_str(&text).unwrap();
            (id, jsonschema::validator_for(&s).unwrap())
        })
        .collect();
    let dir = root().join("crates/runout-cli/tests/cli/snapshots");
    let mut checked = BTreeMap::<String, usize>::new();
    for e in std::fs::read_dir(&dir).unwrap() {
        let p = e.unwrap().path();
        let text = std::fs::read_to_string(&p).unwrap();
        let mut v: serde_json::Value = serde_json::from_str(snapshot_body(&text))
            .unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        unredact(&mut v, true);
        let id = v["schema"].as_str().unwrap_or_default().to_string();
        let Some(validator) = schemas.get(id.as_str()) else {
            continue; // a job not yet in the library (identify, simulate)
        };
        let errors: Vec<String> = validator
            .iter_errors(&v)
            .map(|e| format!("{} at {}", e, e.instance_path()))
            .collect();
        assert!(errors.is_empty(), "{}: {errors:#?}", p.display());
        *checked.entry(id).or_default() += 1;
    }
    // every library report has at least one CLI output checked
    for id in schemas.keys() {
        assert!(
            checked.contains_key(*id),
            "no CLI snapshot of {id}: {checked:?}"
        );
    }
}

#[test]
fn a_wrong_output_is_refused() {
    let (_, _, text) = runout::schema::all()
        .into_iter()
        .find(|(id, _, _)| *id == "runout.shank.stiffness/1")
        .unwrap();
    let s: serde_json::Value = serde_json::from_str(&text).unwrap();
    let v = jsonschema::validator_for(&s).unwrap();
    let body = std::fs::read_to_string(
        root().join("crates/runout-cli/tests/cli/snapshots/cli__snapshots__shank_stiffness.snap"),
    )
    .unwrap();
    let mut good: serde_json::Value = serde_json::from_str(snapshot_body(&body)).unwrap();
    assert!(v.is_valid(&good));
    let mut other_version = good.clone();
    other_version["schema"] = "runout.shank.stiffness/2".into();
    assert!(!v.is_valid(&other_version));
    good["stiffness_N_per_um"] = "1.9 N/um".into();
    assert!(!v.is_valid(&good));
    good.as_object_mut().unwrap().remove("stiffness_N_per_um");
    assert!(!v.is_valid(&good));
}

/// The batch report's snapshot validates only once its redacted wall-clock fields are numbers
/// again: the schema holds them as numbers (the redaction is the snapshot's, not the output's).
#[test]
fn the_batch_snapshot_needs_its_wall_clock_numbers() {
    let (_, _, text) = runout::schema::all()
        .into_iter()
        .find(|(id, _, _)| *id == "runout.batch/1")
        .unwrap();
    let s: serde_json::Value = serde_json::from_str(&text).unwrap();
    let v = jsonschema::validator_for(&s).unwrap();
    let body = std::fs::read_to_string(
        root().join("crates/runout-cli/tests/cli/snapshots/cli__batch_snapshot__batch.snap"),
    )
    .unwrap();
    let mut report: serde_json::Value = serde_json::from_str(snapshot_body(&body)).unwrap();
    assert_eq!(report["elapsed_s"], "[wall-clock]");
    assert!(!v.is_valid(&report));
    unredact(&mut report, true);
    assert!(v.is_valid(&report));
    assert_eq!(report["failed"].as_array().unwrap().len(), 1);
}
