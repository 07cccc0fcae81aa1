//! Sample records as columns: one typed vector per field of the shard's `sample` lines, read
//! generically from each record's JSON fields, so a field the wire format gains later
//! becomes a column without a change here.
//!
//! The fields the format defines today have fixed kinds (so a column's type never depends
//! on the data): `index`, `sample`, `iterations` integers; `theta_p`, `tan_theta_x`,
//! `tan_theta_y`, `decenter_x`, `decenter_y`, `decenter`, `despace`, `residual` (rad, -, -,
//! mm ×4, N) and the optional counts `slack_cables`,
//! `loose_joints` floats, NaN where a record has none (a failed sample); `case`, `status`,
//! `reason` text, empty where absent. Any other field takes the kind of its first value
//! (integer, float, boolean or text; an integer column meeting a fraction becomes float,
//! any other mismatch text) and records where it is absent.

use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyList, PyTuple};
use serde_json::{Map, Value};
use std::collections::HashMap;

/// The values of one column.
#[derive(Debug, Clone, PartialEq)]
enum Values {
    Int(Vec<i64>),
    Float(Vec<f64>),
    Bool(Vec<bool>),
    Text(Vec<String>),
}

impl Values {
    /// An empty column of the kind of `v`, with `rows` absent values before it.
    fn of(v: &Value, rows: usize) -> Self {
        match v {
            Value::Bool(_) => Values::Bool(vec![false; rows]),
            Value::Number(n) if n.as_i64().is_some() => Values::Int(vec![0; rows]),
            Value::Number(_) => Values::Float(vec![f64::NAN; rows]),
            _ => Values::Text(vec![String::new(); rows]),
        }
    }

    fn push_absent(&mut self) {
        match self {
            Values::Int(v) => v.push(0),
            Values::Float(v) => v.push(f64::NAN),
            Values::Bool(v) => v.push(false),
            Values::Text(v) => v.push(String::new()),
        }
    }

    /// Appends `value`, first widening the column if it does not hold values of its kind
    /// (`present` says which earlier rows had a value).
    fn push(&mut self, value: &Value, present: &[bool]) {
        let fits = match (&*self, value) {
            (Values::Int(_), Value::Number(n)) => n.as_i64().is_some(),
            (Values::Float(_), Value::Number(_))
            | (Values::Bool(_), Value::Bool(_))
            | (Values::Text(_), _) => true,
            _ => false,
        };
        if !fits {
            self.widen(value, present);
        }
        match (self, value) {
            (Values::Int(v), Value::Number(n)) => v.push(n.as_i64().unwrap_or_default()),
            (Values::Float(v), Value::Number(n)) => v.push(n.as_f64().unwrap_or(f64::NAN)),
            (Values::Bool(v), Value::Bool(b)) => v.push(*b),
            (Values::Text(v), Value::String(s)) => v.push(s.clone()),
            (Values::Text(v), other) => v.push(other.to_string()),
            (column, _) => column.push_absent(),
        }
    }

    /// Makes the column able to hold `value`: integers become floats for a fraction (NaN
    /// where absent); anything else becomes text (empty where absent).
    fn widen(&mut self, value: &Value, present: &[bool]) {
        fn text<T: ToString>(v: &[T], present: &[bool]) -> Values {
            let cell = |(x, &p): (&T, &bool)| if p { x.to_string() } else { String::new() };
            Values::Text(v.iter().zip(present).map(cell).collect())
        }
        *self = match (&*self, value) {
            (Values::Int(v), Value::Number(_)) => Values::Float(
                v.iter()
                    .zip(present)
                    .map(|(&i, &p)| if p { i as f64 } else { f64::NAN })
                    .collect(),
            ),
            (Values::Int(v), _) => text(v, present),
            (Values::Float(v), _) => text(v, present),
            (Values::Bool(v), _) => text(v, present),
            (Values::Text(v), _) => Values::Text(v.clone()),
        };
    }
}

/// One named column and where its records had a value.
#[derive(Debug, Clone, PartialEq)]
struct Column {
    name: String,
    values: Values,
    present: Vec<bool>,
}

/// The fields of a sample record today, in wire order, with their fixed kinds.
const KNOWN: [(&str, Values); 16] = [
    ("index", Values::Int(Vec::new())),
    ("case", Values::Text(Vec::new())),
    ("sample", Values::Int(Vec::new())),
    ("status", Values::Text(Vec::new())),
    ("iterations", Values::Int(Vec::new())),
    ("theta_p", Values::Float(Vec::new())),
    ("tan_theta_x", Values::Float(Vec::new())),
    ("tan_theta_y", Values::Float(Vec::new())),
    ("decenter_x", Values::Float(Vec::new())),
    ("decenter_y", Values::Float(Vec::new())),
    ("decenter", Values::Float(Vec::new())),
    ("despace", Values::Float(Vec::new())),
    ("residual", Values::Float(Vec::new())),
    ("slack_cables", Values::Float(Vec::new())),
    ("loose_joints", Values::Float(Vec::new())),
    ("reason", Values::Text(Vec::new())),
];

/// Sample records as columns (see the module doc).
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    rows: usize,
    columns: Vec<Column>,
    by_name: HashMap<String, usize>,
}

impl Default for Table {
    fn default() -> Self {
        Self::new()
    }
}

impl Table {
    /// An empty table with the known fields' columns.
    pub fn new() -> Self {
        let columns: Vec<Column> = KNOWN
            .iter()
            .map(|(name, values)| Column {
                name: name.to_string(),
                values: values.clone(),
                present: Vec::new(),
            })
            .collect();
        let by_name = columns
            .iter()
            .enumerate()
            .map(|(i, c)| (c.name.clone(), i))
            .collect();
        Self {
            rows: 0,
            columns,
            by_name,
        }
    }

    /// The number of records.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Appends one record (its `record` tag, if any, is not a column).
    pub fn push(&mut self, record: &Map<String, Value>) {
        let rows = self.rows;
        for (name, value) in record {
            if name == "record" || value.is_null() {
                continue;
            }
            let i = match self.by_name.get(name.as_str()) {
                Some(&i) => i,
                None => {
                    self.columns.push(Column {
                        name: name.clone(),
                        values: Values::of(value, rows),
                        present: vec![false; rows],
                    });
                    self.by_name.insert(name.clone(), self.columns.len() - 1);
                    self.columns.len() - 1
                }
            };
            let column = &mut self.columns[i];
            column.values.push(value, &column.present);
            column.present.push(true);
        }
        self.rows += 1;
        for column in &mut self.columns {
            if column.present.len() < self.rows {
                column.values.push_absent();
                column.present.push(false);
            }
        }
    }

    /// The column `name`'s integers, if it is an integer column (for tests and checks).
    pub fn ints(&self, name: &str) -> Option<&[i64]> {
        match &self.columns[*self.by_name.get(name)?].values {
            Values::Int(v) => Some(v),
            _ => None,
        }
    }

    /// The columns for Python: a list of `(name, kind, data, present)` with `kind` one of
    /// `"int"`, `"float"`, `"bool"`, `"str"`; `data` little-endian `i64`/`f64` bytes, one
    /// byte per boolean, or a list of strings; `present` one byte per record (1 where it
    /// had the field), or `None` when every record had it.
    pub fn to_python<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let columns = self.columns.iter().map(|c| {
            let (kind, data): (&str, Bound<'py, PyAny>) = match &c.values {
                Values::Int(v) => (
                    "int",
                    bytes(py, v.iter().map(|x| x.to_le_bytes())).into_any(),
                ),
                Values::Float(v) => (
                    "float",
                    bytes(py, v.iter().map(|x| x.to_le_bytes())).into_any(),
                ),
                Values::Bool(v) => (
                    "bool",
                    bytes(py, v.iter().map(|&b| [u8::from(b)])).into_any(),
                ),
                Values::Text(v) => ("str", PyList::new(py, v)?.into_any()),
            };
            let present = if c.present.iter().all(|&p| p) {
                py.None().into_bound(py)
            } else {
                bytes(py, c.present.iter().map(|&p| [u8::from(p)])).into_any()
            };
            PyTuple::new(
                py,
                [
                    c.name.clone().into_pyobject(py)?.into_any(),
                    kind.into_pyobject(py)?.into_any(),
                    data,
                    present,
                ],
            )
        });
        PyList::new(py, columns.collect::<PyResult<Vec<_>>>()?)
    }
}

/// Cases as the shard header lists them, for Python: dicts of `name`, `start` (the global
/// index of the first sample), `samples` and `parameters`.
pub fn cases<'py>(
    py: Python<'py>,
    cases: impl Iterator<Item = shard_record::CaseInfo>,
) -> PyResult<Bound<'py, PyList>> {
    let dicts = cases.map(|c| {
        let d = pyo3::types::PyDict::new(py);
        d.set_item("name", c.name)?;
        d.set_item("start", c.start)?;
        d.set_item("samples", c.samples)?;
        d.set_item("parameters", c.parameters)?;
        Ok(d)
    });
    PyList::new(py, dicts.collect::<PyResult<Vec<_>>>()?)
}

/// Python bytes of the concatenated little-endian encodings `parts`.
pub fn bytes<'py, const N: usize>(
    py: Python<'py>,
    parts: impl Iterator<Item = [u8; N]>,
) -> Bound<'py, PyBytes> {
    let v: Vec<u8> = parts.flatten().collect();
    PyBytes::new(py, &v)
}

/// Python bytes of `values` as little-endian `f64`.
pub fn f64_bytes<'py>(py: Python<'py>, values: &[f64]) -> Bound<'py, PyBytes> {
    bytes(py, values.iter().map(|x| x.to_le_bytes()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn table(records: &[Value]) -> Table {
        let mut t = Table::new();
        for r in records {
            t.push(r.as_object().unwrap());
        }
        t
    }

    /// Known fields keep their kinds; a new field becomes a column of its first value's
    /// kind, absent before it appeared; integers meeting a fraction become floats.
    #[test]
    fn fields_become_typed_columns() {
        let t = table(&[
            json!({"record": "sample", "index": 0, "case": "a", "status": "failed", "reason": "r"}),
            json!({"index": 1, "theta_p": 1e-5, "slack_cables": 3, "floating": true, "extra": 2}),
            json!({"index": 2, "extra": 2.5, "note": null}),
        ]);
        assert_eq!(t.rows(), 3);
        assert_eq!(t.ints("index"), Some(&[0, 1, 2][..]));
        let col = |name: &str| &t.columns[t.by_name[name]];
        assert_eq!(
            col("slack_cables").values.nan_free(),
            Values::Float(vec![-1.0, 3.0, -1.0])
        );
        assert_eq!(
            col("floating").values,
            Values::Bool(vec![false, true, false])
        );
        assert_eq!(col("floating").present, [false, true, false]);
        assert_eq!(
            col("extra").values.nan_free(),
            Values::Float(vec![-1.0, 2.0, 2.5])
        );
        assert_eq!(
            col("reason").values,
            Values::Text(vec!["r".into(), String::new(), String::new()])
        );
        assert!(!t.by_name.contains_key("record") && !t.by_name.contains_key("note"));
    }

    impl Values {
        /// NaN as -1, so columns compare with `==`.
        fn nan_free(&self) -> Values {
            match self {
                Values::Float(v) => Values::Float(
                    v.iter()
                        .map(|x| if x.is_nan() { -1.0 } else { *x })
                        .collect(),
                ),
                other => other.clone(),
            }
        }
    }
}
