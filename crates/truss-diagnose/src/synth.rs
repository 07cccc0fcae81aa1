//! `truss synth-measured`: measured data made from a model with an effect the baseline
//! lacks (or none), for testing the diagnosis on data whose hidden effect it is not told.
//! Several effects are hidden at once with `;` between them
//! (`gravity:g_x=1;length_sigma:sigma.longeron=0.012`). A parameter value outside its
//! candidate's plausible range, or not a finite number, is refused naming the parameter.
//!
//! The specimens are samples `0..N` of the baseline case with the effect applied, under the
//! seed `S` given (not the job's: their member errors are independent of the diagnosis's
//! simulation), solved by the job crate's per-sample solve; each written coordinate gets the instrument's
//! noise σ_m·z (z standard normal from the counter-based generator, keyed by `S`). Rows are
//! `specimen,node,x,y,z` (positions in mm, nominal plus displacement plus noise), specimens
//! `S0001`, `S0002`, …; a sample whose solve fails is skipped. With a member file, every
//! member with a length-error distribution is written as drawn (plus noise σ_m).

use crate::candidates::{library, parse_effect};
use crate::comparison::baseline::Baseline;
use crate::comparison::measured::Coordinate;
use crate::comparison::simulate::{Noise, noise_normal, simulate, top_indices};
use crate::errors::DiagnoseError;
use std::io::Write;
use std::path::PathBuf;

/// Options of `truss synth-measured`.
#[derive(Debug, Clone)]
pub struct SynthOptions {
    /// The baseline job.
    pub job: PathBuf,
    /// The case.
    pub case: String,
    /// Number of specimens.
    pub specimens: usize,
    /// Seed of the specimens and their noise.
    pub seed: u64,
    /// `none` or `NAME:P=V,…`; several effects separated by `;`.
    pub effect: String,
    /// Instrument σ_m \[mm\].
    pub measurement_sigma: f64,
    /// Write every node (not only the top surface).
    pub all_nodes: bool,
    /// Also write measured member length errors here.
    pub members_out: Option<PathBuf>,
}

/// Writes the node CSV of measured positions (mm): the header, then for each specimen
/// `S0001, …` the nominal position plus the displacements in `x` (each specimen's x, y, z
/// of every one of `nodes`, in order, as [`Coordinate::of_nodes`] lists them).
pub fn write_specimens(
    out: &mut dyn Write,
    model: &truss_core::Model,
    nodes: &[usize],
    x: &[f64],
) -> std::io::Result<()> {
    writeln!(out, "specimen,node,x,y,z")?;
    for (s, row) in x.chunks_exact(3 * nodes.len()).enumerate() {
        for (k, &node) in nodes.iter().enumerate() {
            let n = &model.nodes()[node];
            writeln!(
                out,
                "S{:04},{},{},{},{}",
                s + 1,
                n.id,
                n.xyz[0] + row[3 * k],
                n.xyz[1] + row[3 * k + 1],
                n.xyz[2] + row[3 * k + 2]
            )?;
        }
    }
    Ok(())
}

/// Writes the node CSV to `out`; returns the number of specimens written.
pub fn synth(options: &SynthOptions, out: &mut dyn Write) -> Result<usize, DiagnoseError> {
    if !(options.measurement_sigma >= 0.0 && options.measurement_sigma.is_finite()) {
        return Err(DiagnoseError::Usage(
            "--measurement-sigma must be a non-negative number of mm".into(),
        ));
    }
    let baseline = Baseline::read(&options.job, &options.case)?;
    let (candidates, _) = library(&baseline);
    let mut edit = baseline.derived_case();
    for effect in options.effect.split(';') {
        if let Some((i, values)) = parse_effect(effect, &candidates)? {
            candidates[i].apply(&values, &mut edit)?;
        }
    }
    let job = baseline.job_of(&edit, options.specimens as u64, Some(options.seed))?;
    let model = job.cases[0].model.clone();
    let top = model
        .top_surface()
        .ok_or_else(|| DiagnoseError::Usage("the model names no top surface".into()))?
        .nodes;
    let nodes: Vec<usize> = if options.all_nodes {
        (0..model.nodes().len()).collect()
    } else {
        top.to_vec()
    };
    let coords = Coordinate::of_nodes(&model, &nodes);
    let top_ix = top_indices(&coords, top).expect("top nodes are written");
    let noise = Noise {
        sigma: options.measurement_sigma,
        seed: options.seed ^ 0x7379_6e74_6865_7469,
    };
    let sim = simulate(
        &job,
        &coords,
        options.specimens,
        Some((noise, top_ix)),
        truss_threads::available(),
    )?;
    let io = |e: std::io::Error| DiagnoseError::io(std::path::Path::new("<stdout>"), e);
    write_specimens(out, &model, &nodes, &sim.x_noisy).map_err(io)?;
    if let Some(path) = &options.members_out {
        let case = &job.cases[0];
        let mut text = String::from("specimen,member,length_error\n");
        // Specimen k is the simulation's row k (as in the node file): its sample's drawn
        // length errors, as the solve used them.
        for (k, errors) in sim.errors.chunks_exact(sim.members).enumerate() {
            for (m, member) in model.members().iter().enumerate() {
                if case.member_errors[m].is_some() {
                    let e = errors[m]
                        + options.measurement_sigma
                            * noise_normal(noise.seed ^ 0x6d65_6d62, k as u64, m as u64);
                    text.push_str(&format!("S{:04},{},{e}\n", k + 1, member.id));
                }
            }
        }
        run_dir::write_file(path, text.as_bytes())?;
    }
    Ok(sim.n)
}
