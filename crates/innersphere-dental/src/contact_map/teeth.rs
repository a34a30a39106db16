//! Regions of an arch by tooth, from a teeth-axes JSON: `{"18": {"c": [x, y, z], "x": [..],
//! "y": [..], "z": [..]}, ...}` (tooth number in the Universal Numbering System → crown
//! centre of mass `c` and the end points of its principal axes, in the arch's own frame and
//! unit; the format of the jaw data's `*teeth_axes*.json`).
//!
//! The one parser of the format ([`Teeth::from_json`], [`Teeth::load`]): `ist
//! occlusion-map`, `ist view` and `ist occlude --landmarks` all read teeth through it. It
//! refuses what would label the wrong teeth: a key that is no tooth number 1–32, a key or a
//! tooth given twice (a JSON reader that keeps the last of two equal keys would silently drop
//! a tooth), a crown centre that is not three finite numbers. Whether the teeth fit the arch
//! they label is [`Teeth::check_against`]'s job (`check.rs`).

use glam::DVec3;
use innersphere::error::{Error, Result};
use serde::de::{Deserialize, Deserializer, MapAccess, Visitor};
use std::path::{Path, PathBuf};

/// One tooth: its number and crown centre (the arch's frame).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Tooth {
    /// Universal Numbering System (1–32).
    pub number: u32,
    /// Crown centre of mass.
    pub centre: DVec3,
}

/// Upper or lower: which arch a tooth number belongs to in the Universal Numbering System
/// (1–16 upper, from the patient's right third molar to the left one; 17–32 lower, from the
/// left third molar to the right one).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Jaw {
    /// The maxillary arch, teeth 1–16.
    Upper,
    /// The mandibular arch, teeth 17–32.
    Lower,
}

impl Jaw {
    /// The arch of tooth `number` (1–32).
    pub fn of(number: u32) -> Jaw {
        if number <= 16 {
            Jaw::Upper
        } else {
            Jaw::Lower
        }
    }

    /// The opposing arch.
    pub fn other(self) -> Jaw {
        match self {
            Jaw::Upper => Jaw::Lower,
            Jaw::Lower => Jaw::Upper,
        }
    }

    /// "upper" or "lower".
    pub fn name(self) -> &'static str {
        match self {
            Jaw::Upper => "upper",
            Jaw::Lower => "lower",
        }
    }

    /// "upper teeth (1–16)" or "lower teeth (17–32)", for messages.
    pub fn describe(self) -> &'static str {
        match self {
            Jaw::Upper => "upper teeth (1–16)",
            Jaw::Lower => "lower teeth (17–32)",
        }
    }
}

/// The teeth of one arch, by number.
#[derive(Debug, Clone, PartialEq)]
pub struct Teeth {
    /// Sorted by number, each number once.
    pub teeth: Vec<Tooth>,
    /// The file they were read from (names it in messages).
    pub source: PathBuf,
}

/// Vertices farther than this from every crown centre (mm) belong to no tooth: a crown is
/// at most about 12 mm across, so 10 mm from its centre reaches the cusps and the contact
/// points of the widest molar, and not the base of a scanned model.
pub const MAX_TOOTH_REACH: f64 = 10.0;

/// A JSON object read in file order, refusing a key given twice (serde_json's `Value` keeps
/// the last of two equal keys without a word).
struct UniqueKeys<V>(Vec<(String, V)>);

impl<'de, V: Deserialize<'de>> Deserialize<'de> for UniqueKeys<V> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct Keys<V>(std::marker::PhantomData<V>);
        impl<'de, V: Deserialize<'de>> Visitor<'de> for Keys<V> {
            type Value = UniqueKeys<V>;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("an object")
            }
            fn visit_map<A: MapAccess<'de>>(
                self,
                mut map: A,
            ) -> std::result::Result<Self::Value, A::Error> {
                let mut out: Vec<(String, V)> = Vec::new();
                // A set, not a scan of `out`: a 1 MiB object can hold 10⁵ keys.
                let mut seen = std::collections::HashSet::new();
                while let Some(key) = map.next_key::<String>()? {
                    if !seen.insert(key.clone()) {
                        return Err(serde::de::Error::custom(format!(
                            "the key \"{}\" appears twice",
                            short(&key)
                        )));
                    }
                    let value = map.next_value::<V>()?;
                    out.push((key, value));
                }
                Ok(UniqueKeys(out))
            }
        }
        d.deserialize_map(Keys(std::marker::PhantomData))
    }
}

/// At most 40 characters of a key, for messages.
fn short(s: &str) -> String {
    if s.chars().count() <= 40 {
        s.to_string()
    } else {
        s.chars().take(40).chain(['…']).collect()
    }
}

impl Teeth {
    /// Parses a teeth-axes JSON (see the module doc); `name` names it in errors
    /// ([`Error::Input`], saying what is wrong and where).
    pub fn from_json(text: &str, name: &Path) -> Result<Teeth> {
        let bad = |m: String| Error::Input {
            path: name.to_path_buf(),
            message: m,
        };
        let entries: UniqueKeys<UniqueKeys<serde_json::Value>> = serde_json::from_str(text)
            .map_err(|e| {
                bad(format!(
                    "not a teeth-axes JSON ({{\"18\": {{\"c\": [x, y, z], …}}, …}}): {e}"
                ))
            })?;
        let mut teeth: Vec<(Tooth, &str)> = Vec::with_capacity(entries.0.len());
        for (k, fields) in &entries.0 {
            let digits = k.trim();
            let number: u32 = Some(digits)
                .filter(|d| !d.is_empty() && d.len() <= 3 && d.bytes().all(|b| b.is_ascii_digit()))
                .and_then(|d| d.parse().ok())
                .filter(|n| (1..=32).contains(n))
                .ok_or_else(|| {
                    bad(format!(
                        "\"{}\" is no tooth number (1–32, the Universal Numbering System)",
                        short(k)
                    ))
                })?;
            if let Some((_, other)) = teeth.iter().find(|(t, _)| t.number == number) {
                return Err(bad(format!(
                    "tooth {number} is given twice (keys \"{other}\" and \"{}\")",
                    short(k)
                )));
            }
            let c = fields
                .0
                .iter()
                .find(|(f, _)| f == "c")
                .and_then(|(_, c)| c.as_array())
                .filter(|c| c.len() == 3)
                .and_then(|c| {
                    let x: Vec<f64> = c.iter().filter_map(|x| x.as_f64()).collect();
                    (x.len() == 3).then(|| DVec3::new(x[0], x[1], x[2]))
                })
                .filter(|c| c.is_finite())
                .ok_or_else(|| {
                    bad(format!(
                        "tooth {number}: its crown centre \"c\" must be 3 finite numbers [x, y, z]"
                    ))
                })?;
            teeth.push((Tooth { number, centre: c }, k));
        }
        if teeth.is_empty() {
            return Err(bad("no teeth: the object is empty".into()));
        }
        let mut teeth: Vec<Tooth> = teeth.into_iter().map(|(t, _)| t).collect();
        teeth.sort_by_key(|t| t.number);
        Ok(Teeth {
            teeth,
            source: name.to_path_buf(),
        })
    }

    /// The teeth files of the generated arch pair [`shapes::arch_pair`](innersphere::shapes::arch_pair)
    /// `(_, teeth)`, (upper, lower), from its crown centres
    /// ([`shapes::arch_pair_crowns`](innersphere::shapes::arch_pair_crowns)): for tests and examples
    /// of the teeth checks.
    pub fn of_arch_pair(teeth: usize) -> (Teeth, Teeth) {
        let (upper, lower) = innersphere::shapes::arch_pair_crowns(teeth);
        let make = |centres: Vec<(u32, DVec3)>, name: &str| Teeth {
            teeth: centres
                .into_iter()
                .map(|(number, centre)| Tooth { number, centre })
                .collect(),
            source: PathBuf::from(format!("generated {name} arch teeth")),
        };
        (make(upper, "upper"), make(lower, "lower"))
    }

    /// The teeth as a teeth-axes JSON, crown centres only (`{"18": {"c": [x, y, z]}, …}`),
    /// which [`from_json`](Self::from_json) reads back to the same teeth.
    pub fn to_json(&self) -> String {
        let map: serde_json::Map<String, serde_json::Value> = self
            .teeth
            .iter()
            .map(|t| {
                (
                    t.number.to_string(),
                    serde_json::json!({ "c": t.centre.to_array() }),
                )
            })
            .collect();
        serde_json::Value::Object(map).to_string()
    }

    /// Reads and parses a teeth-axes JSON file: at most [`TEETH_FILE`](innersphere::input::TEETH_FILE)
    /// bytes from a file, pipe or device (see [`innersphere::input`]).
    pub fn load(path: &Path) -> Result<Teeth> {
        let text = innersphere::input::read_text(path, innersphere::input::TEETH_FILE)?;
        Teeth::from_json(&text, path)
    }

    /// [`Teeth::load`] of a file in `unit` (its mesh's), converted to millimetres as
    /// [`Mesh::load_in`](innersphere::mesh::Mesh::load_in) converts the mesh.
    pub fn load_in(path: &Path, unit: innersphere::mesh::Unit) -> Result<Teeth> {
        Teeth::load(path)?.scaled(unit.to_mm())
    }

    /// The same teeth with every centre multiplied by `factor` (a teeth file is in its
    /// mesh's unit: a mesh converted to millimetres takes its teeth along). Errors on a
    /// factor that is not positive and finite, or centres that would overflow.
    pub fn scaled(&self, factor: f64) -> Result<Teeth> {
        if !(factor.is_finite() && factor > 0.0) {
            return Err(Error::InvalidOption(format!(
                "a teeth file's scale factor must be positive and finite, got {}",
                innersphere::error::num(factor)
            )));
        }
        let teeth: Vec<Tooth> = self
            .teeth
            .iter()
            .map(|t| Tooth {
                number: t.number,
                centre: t.centre * factor,
            })
            .collect();
        if teeth.iter().any(|t| !t.centre.is_finite()) {
            return Err(Error::InvalidOption(format!(
                "{}: scaled by {}, its crown centres overflow",
                self.source.display(),
                innersphere::error::num(factor)
            )));
        }
        Ok(Teeth {
            teeth,
            source: self.source.clone(),
        })
    }

    /// The arch the file labels; an error when it mixes upper and lower teeth (a teeth file
    /// labels one arch: a file holding both would label the other arch's teeth on this one).
    pub fn jaw(&self) -> Result<Jaw> {
        let numbers = |j: Jaw| -> Vec<String> {
            self.teeth
                .iter()
                .filter(|t| Jaw::of(t.number) == j)
                .map(|t| t.number.to_string())
                .collect()
        };
        let (upper, lower) = (numbers(Jaw::Upper), numbers(Jaw::Lower));
        match (upper.is_empty(), lower.is_empty()) {
            (false, true) => Ok(Jaw::Upper),
            (true, false) => Ok(Jaw::Lower),
            _ => Err(Error::Input {
                path: self.source.clone(),
                message: format!(
                    "mixes upper teeth (1–16: {}) and lower teeth (17–32: {}): a teeth file labels one arch",
                    upper.join(", "),
                    lower.join(", ")
                ),
            }),
        }
    }

    /// The tooth (index into `teeth`) of every vertex: the nearest crown centre within
    /// [`MAX_TOOTH_REACH`], else `u32::MAX`.
    pub fn regions(&self, vertices: &[DVec3]) -> Vec<u32> {
        vertices
            .iter()
            .map(|v| {
                let (k, d2) = self
                    .teeth
                    .iter()
                    .enumerate()
                    .map(|(k, t)| (k, (t.centre - *v).length_squared()))
                    .fold((u32::MAX, f64::INFINITY), |(bk, bd), (k, d)| {
                        if d < bd {
                            (k as u32, d)
                        } else {
                            (bk, bd)
                        }
                    });
                if d2 <= MAX_TOOTH_REACH * MAX_TOOTH_REACH {
                    k
                } else {
                    u32::MAX
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Teeth> {
        Teeth::from_json(text, Path::new("t.json"))
    }

    fn message(text: &str) -> String {
        match parse(text) {
            Err(Error::Input { path, message }) => {
                assert_eq!(path, Path::new("t.json"));
                message
            }
            other => panic!("{text}: expected a refusal, got {other:?}"),
        }
    }

    #[test]
    fn parses_and_refuses() {
        let t = parse(r#"{"19": {"c": [1, 2, 3]}, "18": {"c": [0, 0, 0], "x": [1,0,0]}}"#).unwrap();
        assert_eq!(
            t.teeth.iter().map(|t| t.number).collect::<Vec<_>>(),
            [18, 19]
        );
        assert_eq!(t.source, Path::new("t.json"));
        assert_eq!(parse(&t.to_json()).unwrap(), t);
        assert_eq!(t.jaw().unwrap(), Jaw::Lower);
        let r = t.regions(&[DVec3::new(0.9, 2.0, 3.0), DVec3::ZERO, DVec3::splat(50.0)]);
        assert_eq!(r, [1, 0, u32::MAX]);
        for bad in [
            "",
            "[]",
            "{}",
            r#"{"x": {"c": [0,0,0]}}"#,
            r#"{"40": {"c": [0,0,0]}}"#,
            r#"{"0": {"c": [0,0,0]}}"#,
            r#"{"+1": {"c": [0,0,0]}}"#,
            r#"{"incisal": {"c": [0,0,0]}}"#,
            r#"{"1": {"c": [0,0]}}"#,
            r#"{"1": {"c": [0,0,"a"]}}"#,
            r#"{"1": {"c": [0,0,1e400]}}"#,
            r#"{"1": {}}"#,
            r#"{"1": [0,0,0]}"#,
        ] {
            assert!(parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn a_key_or_a_tooth_given_twice_is_refused_by_name() {
        let m = message(r#"{"18": {"c": [0,0,0]}, "19": {"c": [1,0,0]}, "18": {"c": [5,5,5]}}"#);
        assert!(m.contains("the key \"18\" appears twice"), "{m}");
        assert!(m.contains("line 1"), "{m}");
        let m = message(r#"{"18": {"c": [0,0,0]}, "018": {"c": [5,5,5]}}"#);
        assert!(
            m.contains("tooth 18 is given twice (keys \"18\" and \"018\")"),
            "{m}"
        );
        let m = message(r#"{"18": {"c": [0,0,0], "c": [5,5,5]}}"#);
        assert!(m.contains("the key \"c\" appears twice"), "{m}");
    }

    #[test]
    fn an_arch_is_upper_or_lower_never_both() {
        let m = match parse(r#"{"3": {"c": [0,0,0]}, "30": {"c": [1,0,0]}, "5": {"c": [2,0,0]}}"#)
            .unwrap()
            .jaw()
        {
            Err(Error::Input { message, .. }) => message,
            other => panic!("{other:?}"),
        };
        assert!(
            m.contains("mixes upper teeth (1–16: 3, 5) and lower teeth (17–32: 30)"),
            "{m}"
        );
        assert_eq!(Jaw::of(16), Jaw::Upper);
        assert_eq!(Jaw::of(17), Jaw::Lower);
        assert_eq!(Jaw::Upper.other(), Jaw::Lower);
    }

    #[test]
    fn scaled_moves_the_centres_and_refuses_bad_factors() {
        let t = parse(r#"{"3": {"c": [0.01, -0.02, 0.5]}}"#).unwrap();
        let mm = t.scaled(1000.0).unwrap();
        assert_eq!(mm.teeth[0].centre, DVec3::new(10.0, -20.0, 500.0));
        assert_eq!(mm.teeth[0].number, 3);
        for f in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(t.scaled(f).is_err(), "{f}");
        }
        assert!(parse(r#"{"3": {"c": [1e308, 0, 0]}}"#)
            .unwrap()
            .scaled(10.0)
            .is_err());
    }
}
