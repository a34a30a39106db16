//! The scenarios ([`Scenario`]) and their plans: keyframes of lateral position, protrusion
//! and depth (an opening beyond first contact, or a target clearance), drawn from the seed.

use crate::rng::Rng;
use innersphere::{Error, Result};

/// A kind of generated motion.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Scenario {
    /// Chewing cycles: open about 10 mm (hinge rotation), close into contact from the working
    /// side, slide into the bite, clench 0.1–0.25 mm beyond it, grind laterally in light
    /// contact, lift and re-open. About 2 s per cycle.
    Chew,
    /// Plain hinge opening (7–12 mm) and closing into the bite, about 1.2 s per cycle.
    OpenClose,
    /// Mostly lateral and protrusive sliding in light contact (excursions up to 3.5 mm), with
    /// an occasional press into overlap (the first right after the first contact) and an
    /// occasional lift-off. Starts slightly open.
    Grind,
    /// Random contact: a random walk of positions (lateral up to 3.5 mm either side,
    /// protrusive up to 3 mm) in light contact, with presses at random places up to
    /// 0.25 mm past the bite and short lift-offs, in random order and at random speeds; the
    /// first press right after the first contact. Starts slightly open.
    Contact,
}

impl Scenario {
    /// All scenarios.
    pub const ALL: [Scenario; 4] = [
        Scenario::Chew,
        Scenario::OpenClose,
        Scenario::Grind,
        Scenario::Contact,
    ];

    /// `chew`, `open-close`, `grind` or `contact` (what [`FromStr`](std::str::FromStr)
    /// reads; also `random-contact`).
    pub fn name(self) -> &'static str {
        match self {
            Scenario::Chew => "chew",
            Scenario::OpenClose => "open-close",
            Scenario::Grind => "grind",
            Scenario::Contact => "contact",
        }
    }
}

impl std::fmt::Display for Scenario {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Scenario {
    type Err = Error;
    fn from_str(s: &str) -> Result<Scenario> {
        match s.trim().to_ascii_lowercase().replace('_', "-").as_str() {
            "chew" => Ok(Scenario::Chew),
            "open-close" | "openclose" => Ok(Scenario::OpenClose),
            "grind" => Ok(Scenario::Grind),
            "contact" | "random-contact" => Ok(Scenario::Contact),
            _ => Err(Error::InvalidOption(format!(
                "unknown scenario \"{s}\" (expected chew, open-close, grind or contact)"
            ))),
        }
    }
}

/// How deep a keyframe is.
#[derive(Debug, Clone, Copy)]
pub(super) enum Depth {
    /// Open this far beyond first contact at the keyframe's lateral position.
    Open(f64),
    /// In contact with this target clearance.
    Contact(f64),
}

/// A keyframe: its time, lateral shift (to the left), protrusion and depth.
#[derive(Debug, Clone, Copy)]
pub(super) struct Key {
    pub(super) t: f64,
    pub(super) lat: f64,
    pub(super) pro: f64,
    pub(super) depth: Depth,
}

/// Light-contact target clearance.
fn light(rng: &mut Rng, touch: f64) -> f64 {
    -rng.range(0.25, 0.6) * touch
}

/// A plan being written: the keyframes so far and the time of the last.
struct Plan {
    keys: Vec<Key>,
    t: f64,
}

impl Plan {
    fn at(&mut self, dt: f64, lat: f64, pro: f64, depth: Depth) {
        self.t += dt;
        self.keys.push(Key {
            t: self.t,
            lat,
            pro,
            depth,
        });
    }

    /// Repeats the last keyframe after `dt`.
    fn hold(&mut self, dt: f64) {
        if let Some(&k) = self.keys.last() {
            self.at(dt, k.lat, k.pro, k.depth);
        }
    }

    fn last(&self) -> Key {
        self.keys[self.keys.len() - 1]
    }
}

/// The keyframes of [`Scenario::Chew`].
pub(super) fn plan_chew(rng: &mut Rng, seconds: f64, k: f64, touch: f64, c_bite: f64) -> Vec<Key> {
    let mut p = Plan {
        keys: Vec::new(),
        t: 0.0,
    };
    let mut side = rng.sign();
    p.at(
        0.0,
        -0.5 * side * k,
        0.0,
        Depth::Open(rng.range(8.5, 11.5) * k),
    );
    p.hold(rng.range(0.06, 0.14));
    while p.t < seconds + 0.5 {
        // Close from the working side, touch, slide into the bite.
        let (lat_c, pro_c) = (side * rng.range(0.3, 0.8) * k, rng.range(0.0, 0.3) * k);
        p.at(
            rng.range(0.30, 0.40),
            lat_c,
            pro_c,
            Depth::Open(rng.range(0.8, 1.2) * k),
        );
        p.at(
            rng.range(0.10, 0.14),
            lat_c,
            pro_c,
            Depth::Contact(light(rng, touch)),
        );
        p.at(rng.range(0.08, 0.12), 0.0, 0.0, Depth::Contact(c_bite));
        // Clench slightly beyond the bite.
        let clench = c_bite - rng.range(1.0, 2.5) * touch;
        p.at(rng.range(0.06, 0.09), 0.0, 0.0, Depth::Contact(clench));
        p.hold(rng.range(0.10, 0.16));
        p.at(
            rng.range(0.08, 0.12),
            0.0,
            0.0,
            Depth::Contact(light(rng, touch)),
        );
        // Grind out to the working side and back in light contact.
        let (lat_g, pro_g) = (side * rng.range(2.5, 4.5) * k, rng.range(0.3, 1.2) * k);
        p.at(
            rng.range(0.25, 0.35),
            lat_g,
            pro_g,
            Depth::Contact(light(rng, touch)),
        );
        let (lat_h, pro_h) = (side * rng.range(0.0, 0.4) * k, rng.range(0.0, 0.3) * k);
        p.at(
            rng.range(0.25, 0.35),
            lat_h,
            pro_h,
            Depth::Contact(light(rng, touch)),
        );
        // Lift, then open wide, drifting to the next cycle's balancing side.
        p.at(
            rng.range(0.10, 0.14),
            lat_h,
            pro_h,
            Depth::Open(rng.range(0.6, 1.0) * k),
        );
        side = -side;
        let open = Depth::Open(rng.range(8.5, 11.5) * k);
        p.at(
            rng.range(0.25, 0.35),
            -0.5 * side * k,
            rng.range(-0.3, 0.3) * k,
            open,
        );
        p.hold(rng.range(0.05, 0.12));
    }
    p.keys
}

/// The keyframes of [`Scenario::OpenClose`].
pub(super) fn plan_open_close(
    rng: &mut Rng,
    seconds: f64,
    k: f64,
    touch: f64,
    c_bite: f64,
) -> Vec<Key> {
    let mut p = Plan {
        keys: Vec::new(),
        t: 0.0,
    };
    let open = Depth::Open(rng.range(7.0, 12.0) * k);
    p.at(0.0, rng.range(-0.3, 0.3) * k, 0.0, open);
    p.hold(rng.range(0.04, 0.12));
    while p.t < seconds + 0.5 {
        let lat = rng.range(-0.3, 0.3) * k;
        p.at(
            rng.range(0.30, 0.40),
            lat,
            0.0,
            Depth::Open(rng.range(0.5, 0.9) * k),
        );
        p.at(
            rng.range(0.10, 0.15),
            lat,
            0.0,
            Depth::Contact(light(rng, touch)),
        );
        p.at(rng.range(0.08, 0.12), 0.0, 0.0, Depth::Contact(c_bite));
        p.hold(rng.range(0.10, 0.20));
        p.at(
            rng.range(0.10, 0.14),
            0.0,
            0.0,
            Depth::Open(rng.range(0.5, 0.9) * k),
        );
        let open = Depth::Open(rng.range(7.0, 12.0) * k);
        p.at(rng.range(0.25, 0.35), rng.range(-0.3, 0.3) * k, 0.0, open);
        p.hold(rng.range(0.04, 0.12));
    }
    p.keys
}

/// The keyframes of [`Scenario::Grind`].
pub(super) fn plan_grind(rng: &mut Rng, seconds: f64, k: f64, touch: f64, c_bite: f64) -> Vec<Key> {
    let mut p = Plan {
        keys: Vec::new(),
        t: 0.0,
    };
    p.at(0.0, 0.0, 0.0, Depth::Open(rng.range(1.5, 2.5) * k));
    p.hold(rng.range(0.08, 0.15));
    p.at(
        rng.range(0.25, 0.35),
        0.0,
        0.0,
        Depth::Contact(light(rng, touch)),
    );
    let side = rng.sign();
    let mut step = 0usize;
    while p.t < seconds + 0.5 {
        let c = Depth::Contact(light(rng, touch));
        match step % 8 {
            1 | 3 => {
                let s = if step % 8 == 3 { -side } else { side };
                let (lat, pro) = (s * rng.range(1.5, 3.5) * k, rng.range(0.0, 1.0) * k);
                p.at(rng.range(0.30, 0.45), lat, pro, c);
            }
            2 | 4 | 6 => {
                let (lat, pro) = (rng.range(-0.2, 0.2) * k, rng.range(0.0, 0.2) * k);
                p.at(rng.range(0.25, 0.40), lat, pro, c);
            }
            0 => {
                let press = Depth::Contact(c_bite - rng.range(0.5, 1.5) * touch);
                p.at(rng.range(0.12, 0.18), 0.0, 0.0, press);
                p.hold(rng.range(0.06, 0.10));
                p.at(rng.range(0.10, 0.14), 0.0, 0.0, c);
            }
            5 => {
                let (lat, pro) = (rng.range(-0.5, 0.5) * k, rng.range(2.0, 3.5) * k);
                p.at(rng.range(0.30, 0.45), lat, pro, c);
            }
            _ => {
                let Key { lat, pro, .. } = p.last();
                p.at(
                    rng.range(0.10, 0.14),
                    lat,
                    pro,
                    Depth::Open(rng.range(0.6, 1.2) * k),
                );
                p.hold(rng.range(0.08, 0.15));
                p.at(rng.range(0.12, 0.16), lat, pro, c);
            }
        }
        step += 1;
    }
    p.keys
}

/// The keyframes of [`Scenario::Contact`].
pub(super) fn plan_contact(
    rng: &mut Rng,
    seconds: f64,
    k: f64,
    touch: f64,
    c_bite: f64,
) -> Vec<Key> {
    let mut p = Plan {
        keys: Vec::new(),
        t: 0.0,
    };
    p.at(0.0, 0.0, 0.0, Depth::Open(rng.range(1.0, 2.5) * k));
    p.hold(rng.range(0.05, 0.12));
    let (lat, pro) = (rng.range(-0.5, 0.5) * k, rng.range(0.0, 0.5) * k);
    p.at(
        rng.range(0.2, 0.3),
        lat,
        pro,
        Depth::Contact(light(rng, touch)),
    );
    let mut press = true;
    while p.t < seconds + 0.5 {
        let u = rng.unit();
        if press || u < 0.25 {
            // Press where the jaw is, or near the bite.
            let Key { lat, pro, .. } = p.last();
            let near = rng.range(0.0, 1.0);
            let (lat, pro) = (lat * near, pro * near);
            let deep = Depth::Contact(c_bite - rng.range(0.5, 2.5) * touch);
            p.at(rng.range(0.08, 0.18), lat, pro, deep);
            p.hold(rng.range(0.03, 0.12));
            p.at(
                rng.range(0.08, 0.14),
                lat,
                pro,
                Depth::Contact(light(rng, touch)),
            );
            press = false;
        } else if u < 0.4 {
            let Key { lat, pro, .. } = p.last();
            let open = Depth::Open(rng.range(0.3, 1.5) * k);
            p.at(rng.range(0.08, 0.14), lat, pro, open);
            p.hold(rng.range(0.03, 0.10));
            p.at(
                rng.range(0.10, 0.16),
                lat,
                pro,
                Depth::Contact(light(rng, touch)),
            );
        } else {
            let (lat, pro) = (rng.range(-3.5, 3.5) * k, rng.range(0.0, 3.0) * k);
            let c = Depth::Contact(light(rng, touch));
            p.at(rng.range(0.15, 0.45), lat, pro, c);
        }
    }
    p.keys
}
