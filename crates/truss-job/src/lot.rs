//! Length errors shared by a production lot: parts cut from one stock bar, or machined in
//! one batch, share part of their error. A group's length error may add a shared part drawn
//! once per lot and sample, to each member's own scatter:
//!
//! ```json
//! "batten": {"normal": {"sigma": 0.004}, "lot": {"by": "level", "normal": {"sigma": 0.003}}}
//! ```
//!
//! Each of the prism's levels has its battens share one N(0, 0.003²) draw, plus their own
//! N(0, 0.004²) each: member `i` of lot `L` gets
//!
//! ```text
//! e_i = p_i + s_L,    p_i ~ the group's own distribution,   s_L ~ the lot's distribution
//! Var e_i = σ_part² + σ_lot²,    corr(e_i, e_j) = σ_lot² / (σ_lot² + σ_part²)  (i, j in one lot)
//! ```
//!
//! and members of different lots stay independent. A lot with `σ_part = 0`
//! (`{"normal": {"sigma": 0}}`) gives its members identical errors.
//!
//! ## `by`
//!
//! - `"level"` (the prism only): a batten's lot is its level (`batten.K.J`: level K), a
//!   longeron's and a diagonal's its stage (`longeron.S.J`, `diagonal.S.J.a|b`: stage S), in
//!   increasing order.
//! - lists of member ids, for any model: `"by": [["batten.1.0", "batten.1.1"], ["batten.2.0"]]`,
//!   each list one lot, in the order given; a member of the group in no list is a lot of its
//!   own (its shared part drawn for it alone, so every member's error has the same law).
//!
//! A member named twice, one that is not in the group (or not in the model), an empty list
//! and `"level"` on a model file are refused before any work, naming the JSON path
//! (`cases[0].length_errors.batten.lot.by[1][0]: …`). The lot's distribution is any of the
//! job format's ([`crate::distribution`]).
//!
//! ## Draws
//!
//! A group's lot parts come from their own ChaCha20 stream, so that adding a lot changes no
//! other draw (every member's own part is drawn as before, from the sample's stream: see
//! [`crate::sampler`]):
//!
//! ```text
//! key    = SHA-256("truss-mc lot stream v1" ‖ 0x00 ‖ seed as 8 little-endian bytes ‖ case name ‖ 0x00 ‖ group name)
//! stream = k (the sample's index within its case)
//! ```
//!
//! lot `L` (in the order above) taking words `2L` and `2L + 1`, turned into a number as every
//! draw is ([`crate::distribution`]). So a sample's draws still depend only on the job, its
//! seed, the case and the index.

use crate::distribution::DistributionSpec;
use crate::errors::JobError;
use serde::de::{Error as _, MapAccess, Visitor};
use serde::ser::SerializeMap;
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use truss_core::Model;

/// Domain separator of a lot stream's key.
const DOMAIN: &[u8] = b"truss-mc lot stream v1";

/// How a group's members are put into lots, as written.
#[derive(Debug, Clone, PartialEq)]
pub enum LotBy {
    /// The prism's levels (battens) and stages (longerons, diagonals).
    Level,
    /// Lists of member ids, one list per lot.
    Members(Vec<Vec<String>>),
}

impl Serialize for LotBy {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            LotBy::Level => s.serialize_str("level"),
            LotBy::Members(lists) => lists.serialize(s),
        }
    }
}

impl<'de> Deserialize<'de> for LotBy {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let value = serde_json::Value::deserialize(d)?;
        if value.as_str() == Some("level") {
            return Ok(LotBy::Level);
        }
        serde_json::from_value::<Vec<Vec<String>>>(value)
            .map(LotBy::Members)
            .map_err(|_| {
                D::Error::custom(
                    "expected \"level\" or lists of member ids, e.g. \
                     [[\"batten.1.0\", \"batten.1.1\"], [\"batten.2.0\"]]",
                )
            })
    }
}

/// A group's shared lot part as written: `{"by": …, <distribution>}`.
#[derive(Debug, Clone, PartialEq)]
pub struct LotSpec {
    /// How the members are put into lots.
    pub by: LotBy,
    /// The distribution of each lot's shared part \[mm\].
    pub distribution: DistributionSpec,
}

impl Serialize for LotSpec {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        #[derive(Serialize)]
        struct Written<'a> {
            by: &'a LotBy,
            #[serde(flatten)]
            distribution: &'a DistributionSpec,
        }
        Written {
            by: &self.by,
            distribution: &self.distribution,
        }
        .serialize(s)
    }
}

/// Reads the entries of a distribution object, `lot` (if `lot_allowed`) apart: returns the
/// one distribution and the lot, if any.
fn read_entries<'de, A: MapAccess<'de>>(
    mut a: A,
    lot_allowed: bool,
) -> Result<(DistributionSpec, Option<LotSpec>, Option<LotBy>), A::Error> {
    let mut kinds = serde_json::Map::new();
    let (mut lot, mut by) = (None, None);
    while let Some(key) = a.next_key::<String>()? {
        match key.as_str() {
            "lot" if lot_allowed => lot = Some(a.next_value::<LotSpec>()?),
            "by" if !lot_allowed => by = Some(a.next_value::<LotBy>()?),
            _ => {
                let v: serde_json::Value = a.next_value()?;
                kinds.insert(key, v);
            }
        }
    }
    if kinds.is_empty() {
        let known: Vec<String> = DistributionSpec::KINDS
            .iter()
            .map(|k| format!("{{\"{k}\": …}}"))
            .collect();
        return Err(A::Error::custom(format!(
            "a distribution is missing: give one of {}",
            known.join(", ")
        )));
    }
    let distribution = DistributionSpec::deserialize(serde_json::Value::Object(kinds))
        .map_err(|e| A::Error::custom(e.to_string()))?;
    Ok((distribution, lot, by))
}

impl<'de> Deserialize<'de> for LotSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = LotSpec;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a lot: {\"by\": \"level\" or lists of member ids, <distribution>}")
            }
            fn visit_map<A: MapAccess<'de>>(self, a: A) -> Result<LotSpec, A::Error> {
                let (distribution, _, by) = read_entries(a, false)?;
                let by = by.ok_or_else(|| {
                    A::Error::custom(
                        "a lot needs \"by\": \"level\" or lists of member ids, beside its \
                         distribution",
                    )
                })?;
                Ok(LotSpec { by, distribution })
            }
        }
        d.deserialize_map(V)
    }
}

/// A group's length error as written: its members' own distribution, and optionally a
/// shared lot part.
#[derive(Debug, Clone, PartialEq)]
pub struct GroupErrors {
    /// Each member's own part.
    pub part: DistributionSpec,
    /// The shared lot part, if any.
    pub lot: Option<LotSpec>,
}

impl<'de> Deserialize<'de> for GroupErrors {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = GroupErrors;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a distribution, optionally with a \"lot\"")
            }
            fn visit_map<A: MapAccess<'de>>(self, a: A) -> Result<GroupErrors, A::Error> {
                let (part, lot, _) = read_entries(a, true)?;
                Ok(GroupErrors { part, lot })
            }
        }
        d.deserialize_map(V)
    }
}

/// A case's length errors as written: per group its own distribution (the map this derefs
/// to) and, where a group has one, its lot part. Written back as the job format writes it,
/// each lot inside its group's object.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct LengthErrors {
    /// Per group, the members' own distribution.
    pub parts: BTreeMap<String, DistributionSpec>,
    /// Per group with a lot part, the lot.
    pub lots: BTreeMap<String, LotSpec>,
}

impl std::ops::Deref for LengthErrors {
    type Target = BTreeMap<String, DistributionSpec>;
    fn deref(&self) -> &Self::Target {
        &self.parts
    }
}

impl std::ops::DerefMut for LengthErrors {
    fn deref_mut(&mut self) -> &mut Self::Target {
        &mut self.parts
    }
}

impl<'a> IntoIterator for &'a LengthErrors {
    type Item = (&'a String, &'a DistributionSpec);
    type IntoIter = std::collections::btree_map::Iter<'a, String, DistributionSpec>;
    fn into_iter(self) -> Self::IntoIter {
        self.parts.iter()
    }
}

impl From<BTreeMap<String, DistributionSpec>> for LengthErrors {
    fn from(parts: BTreeMap<String, DistributionSpec>) -> Self {
        Self {
            parts,
            lots: BTreeMap::new(),
        }
    }
}

impl FromIterator<(String, DistributionSpec)> for LengthErrors {
    fn from_iter<I: IntoIterator<Item = (String, DistributionSpec)>>(iter: I) -> Self {
        BTreeMap::from_iter(iter).into()
    }
}

impl Serialize for LengthErrors {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        #[derive(Serialize)]
        struct Group<'a> {
            #[serde(flatten)]
            part: &'a DistributionSpec,
            #[serde(skip_serializing_if = "Option::is_none")]
            lot: Option<&'a LotSpec>,
        }
        let mut m = s.serialize_map(Some(self.parts.len()))?;
        for (group, part) in &self.parts {
            let group_errors = Group {
                part,
                lot: self.lots.get(group),
            };
            m.serialize_entry(group, &group_errors)?;
        }
        m.end()
    }
}

impl<'de> Deserialize<'de> for LengthErrors {
    /// Reads `length_errors`, refusing a group named twice (which a plain map would take as
    /// its last value, silently).
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Groups;
        impl<'de> Visitor<'de> for Groups {
            type Value = LengthErrors;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a map from member group to distribution")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut a: A) -> Result<LengthErrors, A::Error> {
                let mut out = LengthErrors::default();
                while let Some(group) = a.next_key::<String>()? {
                    let g: GroupErrors = a.next_value()?;
                    if out.parts.insert(group.clone(), g.part).is_some() {
                        return Err(A::Error::custom(format!(
                            "group {group:?} is given twice: give it one distribution"
                        )));
                    }
                    if let Some(lot) = g.lot {
                        out.lots.insert(group, lot);
                    }
                }
                Ok(out)
            }
        }
        d.deserialize_map(Groups)
    }
}

impl LengthErrors {
    /// Whether no group has a length error.
    pub fn is_empty(&self) -> bool {
        self.parts.is_empty()
    }

    /// The standard deviation of group `g`'s members' errors, own and shared parts together,
    /// `√(σ_part² + σ_lot²)` \[mm\].
    pub fn total_std_dev(&self, group: &str) -> f64 {
        let part = self.parts.get(group).map_or(0.0, |d| d.std_dev());
        let lot = self
            .lots
            .get(group)
            .map_or(0.0, |l| l.distribution.std_dev());
        part.hypot(lot)
    }
}

/// A group's lots, resolved against its case's model.
#[derive(Debug, Clone, PartialEq)]
pub struct CaseLot {
    /// The group's name.
    pub group: String,
    /// The distribution of each lot's shared part \[mm\].
    pub distribution: DistributionSpec,
    /// The members (model indices) of each lot, in lot order.
    pub lots: Vec<Vec<usize>>,
    /// The key of the group's lot stream (see the module doc).
    pub key: [u8; 32],
}

impl CaseLot {
    /// The share of a member's error variance its lot part holds, `σ_lot²/(σ_lot² + σ_part²)`
    /// (0 when both are 0).
    pub fn variance_share(&self, part: &DistributionSpec) -> f64 {
        let (l, p) = (self.distribution.std_dev(), part.std_dev());
        let total = l * l + p * p;
        if total > 0.0 { l * l / total } else { 0.0 }
    }
}

/// The key of the lot stream of `group` in case `case` of a job with seed `seed`.
pub fn lot_key(seed: u64, case: &str, group: &str) -> [u8; 32] {
    let mut h = Sha256::new();
    h.update(DOMAIN);
    h.update([0u8]);
    h.update(seed.to_le_bytes());
    h.update(case.as_bytes());
    h.update([0u8]);
    h.update(group.as_bytes());
    h.finalize().into()
}

/// Resolves group `group`'s lot against `model` (`stages`: the prism's stage count, `None`
/// for a model file), naming faults by their JSON path under `at` (the lot's path).
pub fn resolve(
    lot: &LotSpec,
    group: &str,
    model: &Model,
    stages: Option<usize>,
    key: [u8; 32],
    at: &str,
) -> Result<CaseLot, JobError> {
    let members: Vec<usize> = (0..model.members().len())
        .filter(|&m| model.members()[m].group == group)
        .collect();
    let lots = match &lot.by {
        LotBy::Level => {
            if stages.is_none() {
                return Err(JobError::at(
                    &format!("{at}.by"),
                    "\"level\" names the prism's levels (batten.K.J, longeron.S.J, \
                     diagonal.S.J.a|b) and this case's model is a model file: list the lots' \
                     member ids instead, [[\"id\", …], …]",
                ));
            }
            let mut by_level: BTreeMap<u64, Vec<usize>> = BTreeMap::new();
            for &m in &members {
                let id = &model.members()[m].id;
                let level = id
                    .split('.')
                    .nth(1)
                    .and_then(|k| k.parse::<u64>().ok())
                    .ok_or_else(|| {
                        JobError::at(
                            &format!("{at}.by"),
                            &format!("member {id:?} has no level in its id (group.LEVEL.…)"),
                        )
                    })?;
                by_level.entry(level).or_default().push(m);
            }
            by_level.into_values().collect()
        }
        LotBy::Members(lists) => {
            let mut lot_of: Vec<Option<(usize, usize)>> = vec![None; model.members().len()];
            let mut lots = Vec::with_capacity(lists.len());
            for (i, list) in lists.iter().enumerate() {
                if list.is_empty() {
                    return Err(JobError::at(
                        &format!("{at}.by[{i}]"),
                        "a lot needs at least one member",
                    ));
                }
                let mut lot = Vec::with_capacity(list.len());
                for (j, id) in list.iter().enumerate() {
                    let path = format!("{at}.by[{i}][{j}]");
                    let m = model.member_index(id).ok_or_else(|| {
                        JobError::at(&path, &format!("the model has no member {id:?}"))
                    })?;
                    let its = &model.members()[m].group;
                    if its != group {
                        return Err(JobError::at(
                            &path,
                            &format!(
                                "member {id:?} is not in group {group:?} (it is in {its:?}): a \
                                 lot shares the error of its own group's members"
                            ),
                        ));
                    }
                    if let Some((a, b)) = lot_of[m] {
                        return Err(JobError::at(
                            &path,
                            &format!(
                                "member {id:?} is named twice (also at by[{a}][{b}]): a member \
                                 belongs to one lot"
                            ),
                        ));
                    }
                    lot_of[m] = Some((i, j));
                    lot.push(m);
                }
                lots.push(lot);
            }
            lots.extend(
                members
                    .iter()
                    .filter(|&&m| lot_of[m].is_none())
                    .map(|&m| vec![m]),
            );
            lots
        }
    };
    Ok(CaseLot {
        group: group.to_string(),
        distribution: lot.distribution,
        lots,
        key,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A group with a lot reads and writes back as the job format writes it; one without
    /// writes exactly as a plain distribution.
    #[test]
    fn length_errors_round_trip_with_their_lots() {
        let text = r#"{"batten":{"normal":{"mean":0.0,"sigma":0.004},"lot":{"by":"level","normal":{"mean":0.0,"sigma":0.003}}},"diagonal":{"uniform":{"low":-0.01,"high":0.0},"lot":{"by":[["diagonal.1.0.a","diagonal.1.0.b"]],"constant":{"value":0.001}}},"longeron":{"normal":{"mean":0.0,"sigma":0.004}}}"#;
        let e: LengthErrors = serde_json::from_str(text).unwrap();
        assert_eq!(e.len(), 3);
        assert_eq!(e.lots.len(), 2);
        assert_eq!(e.lots["batten"].by, LotBy::Level);
        assert!((e.total_std_dev("batten") - 0.005).abs() < 1e-15);
        assert_eq!(serde_json::to_string(&e).unwrap(), text);
    }

    /// Lots with the wrong shape are refused saying what a lot is.
    #[test]
    fn malformed_lots_are_refused() {
        for (text, said) in [
            (
                r#"{"normal": {"sigma": 0.01}, "lot": {"normal": {"sigma": 0.01}}}"#,
                "needs \"by\"",
            ),
            (
                r#"{"normal": {"sigma": 0.01}, "lot": {"by": "stage", "normal": {"sigma": 0.01}}}"#,
                "expected \"level\" or lists",
            ),
            (
                r#"{"normal": {"sigma": 0.01}, "lot": {"by": "level"}}"#,
                "a distribution is missing",
            ),
            (
                r#"{"normal": {"sigma": 0.01}, "lot": {"by": "level", "normal": {"sigma": 1}, "uniform": {"low": 0, "high": 1}}}"#,
                "one distribution at a time",
            ),
        ] {
            let m = serde_json::from_str::<GroupErrors>(text)
                .unwrap_err()
                .to_string();
            assert!(m.contains(said), "{text}: {m}");
        }
    }
}
