//! The out-of-balance force and the member states of `W` samples at once: the evaluation of
//! [`evaluate_with`](super::super::evaluate::evaluate_with), with every number a lane of `W`
//! samples of one structure (structure of arrays, `[f64; W]` per quantity).
//!
//! Each lane performs exactly the IEEE operations of the one-sample evaluation, in the same
//! order: no fused multiply-add, no sum across lanes, and a one-sided member's state chosen
//! per lane (both stiffnesses computed, one selected). So a sample's `r`, states and
//! [`Evaluation`] are bit for bit those of the one-sample path, whatever its lane, its
//! neighbours, `W` or the instruction set (tested in `super::tests`).
//!
//! Units as in [`crate::element`]: displacements and lengths \[mm\], forces \[N\],
//! stiffnesses \[N/mm\], energy \[N·mm\].

use super::super::evaluate::{Evaluation, max_abs};
use super::lane::lanes;
use crate::element::{AxialMember, AxialState};
use crate::structure::Structure;

/// One sample's inputs and outputs of an evaluation, moved out of its solver while the
/// lane waits (moving a `Vec` moves three words, never its contents).
#[derive(Debug, Default)]
pub(super) struct EvalBuffers {
    /// The sample's member constants, model order plus joint halves.
    pub members: Vec<AxialMember>,
    /// Each member's `k = E·A/L₀` \[N/mm\].
    pub tension: Vec<f64>,
    /// External load per row, plus the zero slot \[N\].
    pub loads: Vec<f64>,
    /// The point \[mm\].
    pub u: Vec<f64>,
    /// `r = g(u) − f` per row, plus the zero slot \[N\] (output).
    pub r: Vec<f64>,
    /// Each member's state at `u` (output).
    pub states: Vec<AxialState>,
}

/// A member's constants for `W` samples.
#[derive(Debug, Clone, Copy)]
struct MemberLanes<const W: usize> {
    reference: [[f64; W]; 3],
    reference_length: [f64; W],
    initial_stretch: [f64; W],
    compression_ratio: [f64; W],
    sense: [f64; W],
    tension: [f64; W],
}

/// Which sample a lane's cached constants belong to: its solver's address and the
/// solver's sample count.
pub(super) type SampleKey = (usize, u64);

/// The lanes' buffers, kept between evaluations: a lane's member constants and loads are
/// gathered once per sample, its point at every evaluation.
#[derive(Debug)]
pub(super) struct EvalLanes<const W: usize> {
    arch: pulp::Arch,
    cached: [Option<SampleKey>; W],
    members: Vec<MemberLanes<W>>,
    loads: Vec<[f64; W]>,
    u: Vec<[f64; W]>,
    r: Vec<[f64; W]>,
    /// Where an empty lane's states go.
    idle_states: Vec<Vec<AxialState>>,
}

impl<const W: usize> EvalLanes<W> {
    /// Buffers for `structure`; every lane starts as a unit bar at rest (so that an empty
    /// lane computes finite, normal numbers).
    pub(super) fn new(structure: &Structure, arch: pulp::Arch) -> Self {
        let m = structure.members.len();
        let n = structure.free;
        let idle = MemberLanes {
            reference: [[1.0; W], [0.0; W], [0.0; W]],
            reference_length: [1.0; W],
            initial_stretch: [0.0; W],
            compression_ratio: [1.0; W],
            sense: [1.0; W],
            tension: [1.0; W],
        };
        let rest = AxialMember::new([1.0, 0.0, 0.0], 1.0, 0.0, 1.0, 1.0).state([0.0; 3]);
        Self {
            arch,
            cached: [None; W],
            members: vec![idle; m],
            loads: vec![[0.0; W]; n + 1],
            u: vec![[0.0; W]; n + 1],
            r: vec![[0.0; W]; n + 1],
            idle_states: vec![vec![rest; m]; W],
        }
    }

    /// The lane whose cached member constants are those of sample `key`, if one's are.
    pub(super) fn lane_caching(&self, key: SampleKey) -> Option<usize> {
        self.cached.iter().position(|&c| c == Some(key))
    }

    /// The sample whose member constants lane `l` caches, if any.
    pub(super) fn cached_sample(&self, l: usize) -> Option<SampleKey> {
        self.cached[l]
    }

    /// Evaluates the samples of the lanes that hold one (`lanes[l]`: the sample's key, its
    /// inputs and where its results go), all of `structure`; returns each one's
    /// [`Evaluation`].
    pub(super) fn evaluate(
        &mut self,
        structure: &Structure,
        lanes: &mut [Option<(SampleKey, &mut EvalBuffers)>; W],
    ) -> [Option<Evaluation>; W] {
        let n = structure.free;
        for (l, lane) in lanes.iter().enumerate() {
            let Some((key, input)) = lane else {
                continue;
            };
            if self.cached[l] != Some(*key) {
                self.cached[l] = Some(*key);
                for ((ml, m), k) in self
                    .members
                    .iter_mut()
                    .zip(&input.members)
                    .zip(&input.tension)
                {
                    for x in 0..3 {
                        ml.reference[x][l] = m.reference[x];
                    }
                    ml.reference_length[l] = m.reference_length;
                    ml.initial_stretch[l] = m.initial_stretch;
                    ml.compression_ratio[l] = m.compression_ratio;
                    ml.sense[l] = m.sense;
                    ml.tension[l] = *k;
                }
                for (f, x) in self.loads.iter_mut().zip(&input.loads) {
                    f[l] = *x;
                }
            }
            for (ul, x) in self.u[..n].iter_mut().zip(&input.u[..n]) {
                ul[l] = *x;
            }
        }
        let mut idle = self.idle_states.iter_mut();
        let mut states: [&mut [AxialState]; W] = std::array::from_fn(|_| &mut [][..]);
        for (st, lane) in states.iter_mut().zip(lanes.iter_mut()) {
            *st = match lane {
                Some((_, b)) => &mut b.states[..],
                None => &mut idle.next().expect("one idle buffer per lane")[..],
            };
        }
        let (force_scale, strain) = dispatch(
            self.arch,
            Kernel {
                s: structure,
                members: &self.members,
                loads: &self.loads,
                u: &self.u,
                r: &mut self.r,
                states,
            },
        );
        let mut out = [None; W];
        for (l, lane) in lanes.iter_mut().enumerate() {
            let Some((_, output)) = lane else {
                continue;
            };
            for (x, rl) in output.r[..=n].iter_mut().zip(&self.r) {
                *x = rl[l];
            }
            out[l] = Some(Evaluation {
                residual: max_abs(&output.r[..n]),
                force_scale: force_scale[l],
                strain: strain[l],
            });
        }
        out
    }
}

/// The kernel compiled for `arch`: the widest vectors this processor has, chosen at run
/// time by `pulp` (AVX2 where present; the default build targets baseline x86-64, SSE2): the same
/// source, [`kernel`], whose lanes the compiler vectorises; the instruction set changes how
/// many lanes one instruction carries, never an operation of a lane.
fn dispatch<const W: usize>(arch: pulp::Arch, kernel: Kernel<'_, W>) -> ([f64; W], [f64; W]) {
    arch.dispatch(kernel)
}

/// The arguments of [`kernel`], for `pulp`'s dispatch (which compiles
/// [`pulp::WithSimd::with_simd`], and the kernel inlined into it, once per instruction set).
struct Kernel<'k, const W: usize> {
    s: &'k Structure,
    members: &'k [MemberLanes<W>],
    loads: &'k [[f64; W]],
    u: &'k [[f64; W]],
    r: &'k mut [[f64; W]],
    states: [&'k mut [AxialState]; W],
}

impl<const W: usize> pulp::WithSimd for Kernel<'_, W> {
    type Output = ([f64; W], [f64; W]);

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) -> Self::Output {
        kernel(
            self.s,
            self.members,
            self.loads,
            self.u,
            self.r,
            self.states,
        )
    }
}

/// Lane-wise `f(a, b)`.
#[inline(always)]
fn zip<const W: usize>(a: [f64; W], b: [f64; W], f: impl Fn(f64, f64) -> f64) -> [f64; W] {
    std::array::from_fn(|l| f(a[l], b[l]))
}

/// The evaluation of `evaluate_with`, lane by lane (see the module doc): `r = −f`, then
/// member by member the state at `d = u_j − u_i` and `∓N·n` into the rows of its nodes;
/// returns each lane's largest |N| and strain energy `Σ ½·N·e`.
#[inline(always)]
fn kernel<const W: usize>(
    s: &Structure,
    members: &[MemberLanes<W>],
    loads: &[[f64; W]],
    u: &[[f64; W]],
    r: &mut [[f64; W]],
    mut states: [&mut [AxialState]; W],
) -> ([f64; W], [f64; W]) {
    let n = s.free;
    let blocks = n / 3;
    for (ri, f) in r.iter_mut().zip(loads) {
        *ri = f.map(|x| -x);
    }
    let zero = [[0.0; W]; 3];
    let mut force_scale = [0.0f64; W];
    let mut strain = [0.0f64; W];
    for (i, (c, m)) in s.members.iter().zip(members).enumerate() {
        let [a, b] = c.link.ends;
        let ua = if a < blocks {
            [u[3 * a], u[3 * a + 1], u[3 * a + 2]]
        } else {
            zero
        };
        let uj = if b < blocks {
            [u[3 * b], u[3 * b + 1], u[3 * b + 2]]
        } else {
            zero
        };
        let d: [[f64; W]; 3] = std::array::from_fn(|x| zip(uj[x], ua[x], |p, q| p - q));
        let cur: [[f64; W]; 3] = std::array::from_fn(|x| zip(m.reference[x], d[x], |p, q| p + q));
        // One operation at a time over all lanes (so that the compiler vectorises each),
        // each lane's expression exactly `AxialMember::state_with`'s.
        let length: [f64; W] = lanes(|l| {
            (cur[0][l] * cur[0][l] + cur[1][l] * cur[1][l] + cur[2][l] * cur[2][l]).sqrt()
        });
        let stretch_sq: [f64; W] = lanes(|l| {
            2.0 * (m.reference[0][l] * d[0][l]
                + m.reference[1][l] * d[1][l]
                + m.reference[2][l] * d[2][l])
                + (d[0][l] * d[0][l] + d[1][l] * d[1][l] + d[2][l] * d[2][l])
        });
        let elongation =
            lanes(|l| stretch_sq[l] / (length[l] + m.reference_length[l]) + m.initial_stretch[l]);
        let slack: [bool; W] = std::array::from_fn(|l| {
            (m.sense[l] * elongation[l] < 0.0) & (m.compression_ratio[l] < 1.0)
        });
        let soft = zip(m.compression_ratio, m.tension, |p, q| p * q);
        let stiffness = lanes(|l| if slack[l] { soft[l] } else { m.tension[l] });
        let inv = length.map(|x| 1.0 / x);
        let direction: [[f64; W]; 3] = std::array::from_fn(|x| zip(cur[x], inv, |p, q| p * q));
        let force = zip(stiffness, elongation, |p, q| p * q);
        strain = lanes(|l| strain[l] + 0.5 * force[l] * elongation[l]);
        let abs = force.map(f64::abs);
        force_scale = lanes(|l| {
            if abs[l] > force_scale[l] {
                abs[l]
            } else {
                force_scale[l]
            }
        });
        let fk: [[f64; W]; 3] = std::array::from_fn(|x| zip(force, direction[x], |p, q| p * q));
        for (l, st) in states.iter_mut().enumerate() {
            st[i] = AxialState {
                direction: [direction[0][l], direction[1][l], direction[2][l]],
                length: length[l],
                elongation: elongation[l],
                force: force[l],
                stiffness: stiffness[l],
                slack: slack[l],
            };
        }
        if c.link.masked {
            let dof = c.link.dofs;
            for x in 0..3 {
                r[dof[x]] = zip(r[dof[x]], fk[x], |p, q| p - q);
                r[dof[3 + x]] = zip(r[dof[3 + x]], fk[x], |p, q| p + q);
            }
        } else {
            if a < blocks {
                for x in 0..3 {
                    r[3 * a + x] = zip(r[3 * a + x], fk[x], |p, q| p - q);
                }
            }
            if b < blocks {
                for x in 0..3 {
                    r[3 * b + x] = zip(r[3 * b + x], fk[x], |p, q| p + q);
                }
            }
        }
    }
    r[n] = [0.0; W];
    (force_scale, strain)
}
