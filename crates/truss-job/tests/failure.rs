//! A failed sample's reason says what the user can do about it: where the model's slack
//! cables are solved at their limit (pin joints in free play, ratio 0), the reason names the
//! regularising ratio and the README section; where the bars frame the tilt it is the
//! solver's words alone. The failure is forced by allowing one Newton iteration.

use std::path::Path;
use truss_core::SolveOptions;
use truss_job::Job;
use truss_job::solve::{Outcome, SampleSolver};

fn reason(job: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../jobs")
        .join(job);
    let job = Job::read(&path).unwrap();
    let options = SolveOptions {
        max_iterations: 1,
        ..SolveOptions::default()
    };
    match SampleSolver::with_options(&job, options).solve(0).outcome {
        Outcome::Failed(reason) => reason,
        Outcome::Converged(c) => panic!("{job:?} sample 0 converged in one iteration: {c:?}"),
    }
}

#[test]
fn a_failure_at_the_limit_names_the_regularising_ratio() {
    let at_limit = reason("paper-4.2.3.json");
    assert!(at_limit.contains("compression_ratio"), "{at_limit}");
    assert!(at_limit.contains("Slack cables"), "{at_limit}");
    let framed = reason("paper-3.1.json");
    assert!(!framed.contains("compression_ratio"), "{framed}");
}
