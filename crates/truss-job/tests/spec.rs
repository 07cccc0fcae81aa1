//! The job spec is readable and writable: every job in `jobs/` read, written and read again
//! gives the same spec and the same job id; and a spec edited as a value (no JSON text in
//! between) validates like the file it stands for.

use std::path::Path;
use truss_job::Job;
use truss_job::distribution::{DistributionSpec, Normal};
use truss_job::job::{JobSpec, ModelSpec};

fn jobs_dir() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../jobs")
}

#[test]
fn every_job_round_trips() {
    let mut seen = 0;
    for entry in std::fs::read_dir(jobs_dir()).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "json") {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap();
        let spec = JobSpec::from_json(&text).unwrap();
        let again = JobSpec::from_json(&spec.to_json()).unwrap();
        assert_eq!(again, spec, "{}", path.display());
        let base = path.parent().unwrap();
        let (a, b) = (Job::new(&spec, base).unwrap(), Job::read(&path).unwrap());
        assert_eq!(a.id, b.id, "{}", path.display());
        seen += 1;
    }
    assert!(seen >= 4, "{seen} jobs");
}

#[test]
fn a_typed_edit_is_the_job_it_writes() {
    let text = std::fs::read_to_string(jobs_dir().join("paper-4.2.3.json")).unwrap();
    let mut spec = JobSpec::from_json(&text).unwrap();
    let case = &mut spec.cases[0];
    case.length_errors.insert(
        "longeron".into(),
        DistributionSpec::Normal(Normal {
            mean: 0.001,
            sigma: 0.01,
        }),
    );
    if let Some(ModelSpec::Prism(p)) = &mut case.model {
        p.stages = 4;
    }
    let edited = Job::new(&spec, Path::new(".")).unwrap();
    let written = Job::from_json(&spec.to_json(), Path::new(".")).unwrap();
    assert_eq!(edited.id, written.id);
    assert_eq!(edited.cases[0].model.members().len(), 4 * 12 + 3);
    let original = Job::from_json(&text, Path::new(".")).unwrap();
    assert_ne!(edited.id, original.id);
}
