//! The prism's options as a job file writes them: `{"stages": 5, "side": 380, …}`, every
//! field optional with Table 1's value as its default ([`PrismOptions::default`]), unknown
//! fields refused. `diagonal_length` is a number of mm or `"exact"` (the face diagonal
//! √(l² + h²)); `backlash` is `true`, `false`, or an object overriding some of `clearance`,
//! `tension_factor` and `compression_ratio`. Written back, only the fields that differ from
//! the defaults appear (and `stages`, always), so a job stays as short as it was written.

use crate::prism::{BacklashOptions, PrismOptions};
use serde::de::Error as _;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// A diagonal natural length: a number of mm, or `"exact"`.
#[derive(Deserialize)]
#[serde(untagged)]
enum DiagonalLength {
    Value(f64),
    Word(String),
}

/// The backlash field: `true`/`false`, or options over the defaults.
#[derive(Deserialize)]
#[serde(untagged)]
enum BacklashField {
    Enabled(bool),
    Options(BacklashOptions),
}

/// The prism's fields as written (all optional).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Written {
    stages: Option<usize>,
    side: Option<f64>,
    height: Option<f64>,
    batten_area: Option<f64>,
    batten_modulus: Option<f64>,
    longeron_area: Option<f64>,
    longeron_modulus: Option<f64>,
    diagonal_area: Option<f64>,
    diagonal_modulus: Option<f64>,
    diagonal_length: Option<DiagonalLength>,
    compression_ratio: Option<f64>,
    backlash: Option<BacklashField>,
}

impl<'de> Deserialize<'de> for PrismOptions {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let w = Written::deserialize(d)?;
        let t = PrismOptions::default();
        Ok(PrismOptions {
            stages: w.stages.unwrap_or(t.stages),
            side: w.side.unwrap_or(t.side),
            height: w.height.unwrap_or(t.height),
            batten_area: w.batten_area.unwrap_or(t.batten_area),
            batten_modulus: w.batten_modulus.unwrap_or(t.batten_modulus),
            longeron_area: w.longeron_area.unwrap_or(t.longeron_area),
            longeron_modulus: w.longeron_modulus.unwrap_or(t.longeron_modulus),
            diagonal_area: w.diagonal_area.unwrap_or(t.diagonal_area),
            diagonal_modulus: w.diagonal_modulus.unwrap_or(t.diagonal_modulus),
            diagonal_length: match w.diagonal_length {
                None => t.diagonal_length,
                Some(DiagonalLength::Value(v)) => Some(v),
                Some(DiagonalLength::Word(w)) if w == "exact" => None,
                Some(DiagonalLength::Word(w)) => {
                    return Err(D::Error::custom(format!(
                        "diagonal_length must be a number of mm or \"exact\", got {w:?}"
                    )));
                }
            },
            compression_ratio: w.compression_ratio.unwrap_or(t.compression_ratio),
            backlash: match w.backlash {
                None | Some(BacklashField::Enabled(false)) => None,
                Some(BacklashField::Enabled(true)) => Some(BacklashOptions::default()),
                Some(BacklashField::Options(b)) => Some(b),
            },
        })
    }
}

impl Serialize for PrismOptions {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde_json::{Map, Value, json};
        let t = PrismOptions::default();
        let mut m = Map::new();
        m.insert("stages".into(), json!(self.stages));
        let mut put = |key: &str, v: f64, default: f64| {
            if v != default {
                m.insert(key.into(), json!(v));
            }
        };
        put("side", self.side, t.side);
        put("height", self.height, t.height);
        put("batten_area", self.batten_area, t.batten_area);
        put("batten_modulus", self.batten_modulus, t.batten_modulus);
        put("longeron_area", self.longeron_area, t.longeron_area);
        put(
            "longeron_modulus",
            self.longeron_modulus,
            t.longeron_modulus,
        );
        put("diagonal_area", self.diagonal_area, t.diagonal_area);
        put(
            "diagonal_modulus",
            self.diagonal_modulus,
            t.diagonal_modulus,
        );
        put(
            "compression_ratio",
            self.compression_ratio,
            t.compression_ratio,
        );
        if self.diagonal_length != t.diagonal_length {
            let v = self.diagonal_length.map_or(json!("exact"), |v| json!(v));
            m.insert("diagonal_length".into(), v);
        }
        if let Some(b) = &self.backlash {
            let v = if *b == BacklashOptions::default() {
                Value::Bool(true)
            } else {
                serde_json::to_value(b).map_err(serde::ser::Error::custom)?
            };
            m.insert("backlash".into(), v);
        }
        m.serialize(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `{"stages": 3}` is Table 1 with 3 stages; written back, it is `{"stages": 3}` again;
    /// every field and form round-trips.
    #[test]
    fn defaults_fill_in_and_round_trip() {
        let o: PrismOptions = serde_json::from_str(r#"{"stages": 3}"#).unwrap();
        assert_eq!(o, PrismOptions::with_stages(3));
        assert_eq!(serde_json::to_string(&o).unwrap(), r#"{"stages":3}"#);
        let text = r#"{"stages":2,"side":400.0,"diagonal_length":"exact","backlash":{"clearance":0.02,"tension_factor":100000.0,"compression_ratio":0.0}}"#;
        let o: PrismOptions = serde_json::from_str(text).unwrap();
        assert_eq!(o.diagonal_length, None);
        assert_eq!(o.backlash.unwrap().clearance, 0.02);
        let back: PrismOptions = serde_json::from_str(&serde_json::to_string(&o).unwrap()).unwrap();
        assert_eq!(back, o);
        let on: PrismOptions = serde_json::from_str(r#"{"stages": 1, "backlash": true}"#).unwrap();
        assert_eq!(on.backlash, Some(BacklashOptions::default()));
        assert!(
            serde_json::to_string(&on)
                .unwrap()
                .contains(r#""backlash":true"#)
        );
    }

    /// Unknown fields and a bad diagonal word are refused.
    #[test]
    fn faults_are_refused() {
        assert!(serde_json::from_str::<PrismOptions>(r#"{"stagse": 3}"#).is_err());
        let e = serde_json::from_str::<PrismOptions>(r#"{"diagonal_length": "long"}"#);
        assert!(e.unwrap_err().to_string().contains("exact"));
        assert!(
            serde_json::from_str::<PrismOptions>(r#"{"backlash": {"clearence": 0.01}}"#).is_err()
        );
    }
}
