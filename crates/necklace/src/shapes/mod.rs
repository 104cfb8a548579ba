//! Analytic test shapes with known necks: the ground truth of the test suite.
//!
//! Each shape is a signed distance function (negative inside) built from balls,
//! capsules and tori joined by smooth unions, meshed by marching tetrahedra on a regular
//! lattice into a closed, manifold, outward-oriented triangle mesh (see `marching`).
//! Every shape states its genus and its expected necks ([`ExpectedNeck`]): how many
//! handle and tunnel loops, where, and how long when the length is known in closed form
//! (a neck of radius r has a tightest loop of length 2πr).
//!
//! Units are arbitrary lengths; every shape is centred at the origin, lies flat in the
//! xy-plane where that matters, and takes its parameters by name ([`ParamSpec`]). The
//! universal parameter `res` is the number of lattice cells along the longest side of the
//! shape's bounding box.
//!
//! Entry point: [`Shape::from_name`] then [`Shape::mesh`].

mod marching;
mod sdf;

use std::f64::consts::PI;
use std::fmt;

use serde::Serialize;

use crate::error::{Error, Result};
use crate::mesh::SurfaceMesh;

/// The generated shapes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ShapeKind {
    /// A ball: genus 0, no neck.
    Sphere,
    /// A round torus: genus 1.
    Torus,
    /// A torus whose tube radius varies around the ring: a well-defined thin side.
    VaryingTorus,
    /// Two balls joined by a thin cylinder.
    Dumbbell,
    /// A row of balls joined by thin cylinders.
    Chain,
    /// Two tori merged side by side: genus 2.
    Eight,
    /// A row of merged tori: genus g.
    Pretzel,
}

/// A named numeric parameter of a shape, with its default and allowed range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParamSpec {
    /// Name used with `--param name=value`.
    pub name: &'static str,
    /// Value when not given.
    pub default: f64,
    /// Smallest allowed value.
    pub min: f64,
    /// Largest allowed value.
    pub max: f64,
    /// Whether the value must be a whole number.
    pub integer: bool,
    /// What it means.
    pub doc: &'static str,
}

const fn real(
    name: &'static str,
    default: f64,
    min: f64,
    max: f64,
    doc: &'static str,
) -> ParamSpec {
    ParamSpec {
        name,
        default,
        min,
        max,
        integer: false,
        doc,
    }
}

const fn whole(
    name: &'static str,
    default: f64,
    min: f64,
    max: f64,
    doc: &'static str,
) -> ParamSpec {
    ParamSpec {
        name,
        default,
        min,
        max,
        integer: true,
        doc,
    }
}

const RES_DOC: &str = "lattice cells along the longest side of the bounding box";
const BLEND_DOC: &str = "width of the smooth union where parts meet (0 = sharp crease)";

const SPHERE: &[ParamSpec] = &[
    real("r", 1.0, 1e-6, 1e6, "radius"),
    whole("res", 24.0, 4.0, 1000.0, RES_DOC),
];
const TORUS: &[ParamSpec] = &[
    real("R", 1.0, 1e-6, 1e6, "radius of the core circle"),
    real("r", 0.3, 1e-6, 1e6, "tube radius (< R)"),
    whole("res", 48.0, 4.0, 1000.0, RES_DOC),
];
const VARYING_TORUS: &[ParamSpec] = &[
    real("R", 1.0, 1e-6, 1e6, "radius of the core circle"),
    real(
        "r0",
        0.3,
        1e-6,
        1e6,
        "mean tube radius; the tube radius is r0 (1 + a cos θ)",
    ),
    real(
        "a",
        0.4,
        0.0,
        0.95,
        "relative variation of the tube radius (thin side at θ = π, on −x)",
    ),
    whole("res", 64.0, 4.0, 1000.0, RES_DOC),
];
const DUMBBELL: &[ParamSpec] = &[
    real("radius", 0.5, 1e-6, 1e6, "radius of each ball"),
    real(
        "offset",
        0.9,
        1e-6,
        1e6,
        "the balls are centred at x = ±offset (> radius)",
    ),
    real(
        "neck",
        0.15,
        1e-6,
        1e6,
        "radius of the joining cylinder (< radius)",
    ),
    real("blend", 0.05, 0.0, 1e6, BLEND_DOC),
    whole("res", 64.0, 4.0, 1000.0, RES_DOC),
];
const CHAIN: &[ParamSpec] = &[
    whole("count", 3.0, 2.0, 100.0, "number of balls"),
    real("radius", 0.5, 1e-6, 1e6, "radius of each ball"),
    real(
        "spacing",
        1.8,
        1e-6,
        1e6,
        "distance between neighbouring ball centres (> 2 radius)",
    ),
    real(
        "neck",
        0.15,
        1e-6,
        1e6,
        "radius of the joining cylinders (< radius)",
    ),
    real("blend", 0.05, 0.0, 1e6, BLEND_DOC),
    whole("res", 96.0, 4.0, 1000.0, RES_DOC),
];
const EIGHT: &[ParamSpec] = &[
    real("R", 1.0, 1e-6, 1e6, "core radius of each ring"),
    real("r", 0.3, 1e-6, 1e6, "tube radius (< R)"),
    real(
        "c",
        1.1,
        1e-6,
        1e6,
        "ring centres at x = ±c, with R < c < R + r",
    ),
    real("blend", 0.1, 0.0, 1e6, BLEND_DOC),
    whole("res", 72.0, 4.0, 1000.0, RES_DOC),
];
const PRETZEL: &[ParamSpec] = &[
    whole("g", 3.0, 1.0, 50.0, "genus: number of rings in the row"),
    real("R", 1.0, 1e-6, 1e6, "core radius of each ring"),
    real("r", 0.3, 1e-6, 1e6, "tube radius (< R)"),
    real(
        "c",
        1.1,
        1e-6,
        1e6,
        "half the distance between neighbouring ring centres (R < c < R + r)",
    ),
    real("blend", 0.1, 0.0, 1e6, BLEND_DOC),
    whole("res", 96.0, 4.0, 1000.0, RES_DOC),
];

impl ShapeKind {
    /// Every shape, in documentation order.
    pub const ALL: [ShapeKind; 7] = [
        ShapeKind::Sphere,
        ShapeKind::Torus,
        ShapeKind::VaryingTorus,
        ShapeKind::Dumbbell,
        ShapeKind::Chain,
        ShapeKind::Eight,
        ShapeKind::Pretzel,
    ];

    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            ShapeKind::Sphere => "sphere",
            ShapeKind::Torus => "torus",
            ShapeKind::VaryingTorus => "varying-torus",
            ShapeKind::Dumbbell => "dumbbell",
            ShapeKind::Chain => "chain",
            ShapeKind::Eight => "eight",
            ShapeKind::Pretzel => "pretzel",
        }
    }

    /// The shape with this name.
    pub fn from_name(name: &str) -> Result<ShapeKind> {
        ShapeKind::ALL
            .into_iter()
            .find(|k| k.name() == name)
            .ok_or_else(|| {
                let names: Vec<&str> = ShapeKind::ALL.iter().map(|k| k.name()).collect();
                Error::invalid_argument(format!(
                    "unknown shape '{name}' (known: {})",
                    names.join(", ")
                ))
            })
    }

    /// Its parameters, with defaults.
    pub fn params(self) -> &'static [ParamSpec] {
        match self {
            ShapeKind::Sphere => SPHERE,
            ShapeKind::Torus => TORUS,
            ShapeKind::VaryingTorus => VARYING_TORUS,
            ShapeKind::Dumbbell => DUMBBELL,
            ShapeKind::Chain => CHAIN,
            ShapeKind::Eight => EIGHT,
            ShapeKind::Pretzel => PRETZEL,
        }
    }

    /// One sentence: what the shape is and which necks it has.
    pub fn description(self) -> &'static str {
        match self {
            ShapeKind::Sphere => "ball of radius r; genus 0, no neck inside or outside",
            ShapeKind::Torus => {
                "round torus; genus 1; handle: every meridian (length 2πr) is equally narrow \
                 (degenerate); tunnel: the inner equator, length 2π(R − r)"
            }
            ShapeKind::VaryingTorus => {
                "torus with tube radius r0(1 + a cos θ); genus 1; one handle at the thin side \
                 (x = −R), length 2π r0 (1 − a); one tunnel around the hole"
            }
            ShapeKind::Dumbbell => {
                "two balls joined by a cylinder of radius neck; genus 0; one handle at the \
                 origin, length 2π neck"
            }
            ShapeKind::Chain => {
                "count balls in a row joined by cylinders of radius neck; genus 0; count − 1 \
                 handles midway between the balls, each of length 2π neck"
            }
            ShapeKind::Eight => {
                "two tori of tube radius r merged side by side; genus 2; two handles (length \
                 2πr, at the far side of each ring by symmetry) and two tunnels (one per hole)"
            }
            ShapeKind::Pretzel => {
                "g tori of tube radius r merged in a row; genus g; handles of length 2πr (one at \
                 the far side of each end ring, two at ±y on each middle ring: 2g − 2 for \
                 g ≥ 2) and g tunnels (one per hole)"
            }
        }
    }
}

impl fmt::Display for ShapeKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Whether a neck is lassoed inside the solid or in the space around it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum NeckKind {
    /// A loop around a narrow part of the solid (found in the inside volume).
    Handle,
    /// A loop around a narrow part of the outside space, e.g. around a hole.
    Tunnel,
}

/// A neck a shape is known to have.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ExpectedNeck {
    /// Handle or tunnel.
    pub kind: NeckKind,
    /// Length of the tightest loop, when known in closed form.
    pub length: Option<f64>,
    /// Centre of the tightest loop, when fixed by symmetry.
    pub center: Option<[f64; 3]>,
    /// How the answer is known.
    pub note: &'static str,
}

/// A generated shape: a kind and a value for each of its parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct Shape {
    kind: ShapeKind,
    values: Vec<f64>,
}

impl Shape {
    /// The shape with its default parameters.
    pub fn new(kind: ShapeKind) -> Shape {
        Shape {
            kind,
            values: kind.params().iter().map(|p| p.default).collect(),
        }
    }

    /// A shape by name, with `name=value` overrides; checks names, ranges and the
    /// constraints between parameters.
    pub fn from_name(name: &str, params: &[(String, f64)]) -> Result<Shape> {
        let mut shape = Shape::new(ShapeKind::from_name(name)?);
        for (key, value) in params {
            shape = shape.with(key, *value)?;
        }
        shape.check()?;
        Ok(shape)
    }

    /// Set one parameter (range-checked; cross-parameter constraints are checked by
    /// [`Shape::mesh`] and [`Shape::from_name`]).
    pub fn with(mut self, name: &str, value: f64) -> Result<Shape> {
        let specs = self.kind.params();
        let Some(i) = specs.iter().position(|p| p.name == name) else {
            let names: Vec<&str> = specs.iter().map(|p| p.name).collect();
            return Err(Error::invalid_argument(format!(
                "shape '{}' has no parameter '{name}' (it has: {})",
                self.kind,
                names.join(", ")
            )));
        };
        let spec = specs[i];
        if !value.is_finite() || value < spec.min || value > spec.max {
            return Err(Error::invalid_argument(format!(
                "{}: {name} = {value} is outside [{}, {}]",
                self.kind, spec.min, spec.max
            )));
        }
        if spec.integer && value.fract() != 0.0 {
            return Err(Error::invalid_argument(format!(
                "{}: {name} must be a whole number, got {value}",
                self.kind
            )));
        }
        self.values[i] = value;
        Ok(self)
    }

    /// The shape's kind.
    pub fn kind(&self) -> ShapeKind {
        self.kind
    }

    /// The value of parameter `name` (panics only on a name the kind does not have,
    /// which is a programming error, never input).
    pub fn param(&self, name: &str) -> f64 {
        let i = self
            .kind
            .params()
            .iter()
            .position(|p| p.name == name)
            .unwrap_or_else(|| panic!("shape {} has no parameter {name}", self.kind));
        self.values[i]
    }

    /// All parameters as `(name, value)`.
    pub fn params(&self) -> Vec<(&'static str, f64)> {
        self.kind
            .params()
            .iter()
            .zip(&self.values)
            .map(|(s, &v)| (s.name, v))
            .collect()
    }

    /// Check the constraints between parameters.
    pub fn check(&self) -> Result<()> {
        let p = |n| self.param(n);
        let fail = |msg: String| Err(Error::invalid_argument(format!("{}: {msg}", self.kind)));
        match self.kind {
            ShapeKind::Sphere => Ok(()),
            ShapeKind::Torus | ShapeKind::Eight | ShapeKind::Pretzel if p("r") >= p("R") => {
                fail(format!("tube radius r = {} must be < R = {}", p("r"), p("R")))
            }
            ShapeKind::Eight | ShapeKind::Pretzel if !(p("c") > p("R") && p("c") < p("R") + p("r")) => {
                fail(format!(
                    "c = {} must lie between R = {} and R + r = {} so the rings merge without crossing",
                    p("c"),
                    p("R"),
                    p("R") + p("r")
                ))
            }
            ShapeKind::VaryingTorus if p("r0") * (1.0 + p("a")) >= p("R") => fail(format!(
                "the thickest tube radius r0 (1 + a) = {} must be < R = {}",
                p("r0") * (1.0 + p("a")),
                p("R")
            )),
            ShapeKind::Dumbbell if p("offset") <= p("radius") => fail(format!(
                "offset = {} must exceed radius = {} (the balls would overlap)",
                p("offset"),
                p("radius")
            )),
            ShapeKind::Chain if p("spacing") <= 2.0 * p("radius") => fail(format!(
                "spacing = {} must exceed 2 radius = {} (the balls would overlap)",
                p("spacing"),
                2.0 * p("radius")
            )),
            ShapeKind::Dumbbell | ShapeKind::Chain if p("neck") >= p("radius") => fail(format!(
                "neck = {} must be < radius = {}",
                p("neck"),
                p("radius")
            )),
            _ => Ok(()),
        }
    }

    /// Genus of the surface.
    pub fn genus(&self) -> usize {
        match self.kind {
            ShapeKind::Sphere | ShapeKind::Dumbbell | ShapeKind::Chain => 0,
            ShapeKind::Torus | ShapeKind::VaryingTorus => 1,
            ShapeKind::Eight => 2,
            ShapeKind::Pretzel => self.param("g") as usize,
        }
    }

    /// Centres of the balls (dumbbell, chain) along the x axis.
    fn ball_centres(&self) -> Vec<[f64; 3]> {
        match self.kind {
            ShapeKind::Dumbbell => {
                let d = self.param("offset");
                vec![[-d, 0.0, 0.0], [d, 0.0, 0.0]]
            }
            ShapeKind::Chain => {
                let n = self.param("count") as usize;
                let s = self.param("spacing");
                (0..n)
                    .map(|i| [(i as f64 - (n as f64 - 1.0) / 2.0) * s, 0.0, 0.0])
                    .collect()
            }
            _ => Vec::new(),
        }
    }

    /// Centres of the rings (eight, pretzel) along the x axis.
    fn ring_centres(&self) -> Vec<[f64; 3]> {
        let g = match self.kind {
            ShapeKind::Eight => 2,
            ShapeKind::Pretzel => self.param("g") as usize,
            _ => return Vec::new(),
        };
        let c = self.param("c");
        (0..g)
            .map(|i| [(2.0 * i as f64 - (g as f64 - 1.0)) * c, 0.0, 0.0])
            .collect()
    }

    /// The signed distance function (negative inside).
    pub fn sdf(&self, p: [f64; 3]) -> f64 {
        let o = [0.0; 3];
        match self.kind {
            ShapeKind::Sphere => sdf::ball(p, o, self.param("r")),
            ShapeKind::Torus => {
                let r = self.param("r");
                sdf::torus(p, o, self.param("R"), |_| r)
            }
            ShapeKind::VaryingTorus => {
                let (r0, a) = (self.param("r0"), self.param("a"));
                sdf::torus(p, o, self.param("R"), |theta| r0 * (1.0 + a * theta.cos()))
            }
            ShapeKind::Dumbbell | ShapeKind::Chain => {
                let (radius, neck, k) = (
                    self.param("radius"),
                    self.param("neck"),
                    self.param("blend"),
                );
                let centres = self.ball_centres();
                let mut d = f64::INFINITY;
                for c in &centres {
                    d = sdf::smooth_union(d, sdf::ball(p, *c, radius), k);
                }
                for w in centres.windows(2) {
                    d = sdf::smooth_union(d, sdf::capsule(p, w[0], w[1], neck), k);
                }
                d
            }
            ShapeKind::Eight | ShapeKind::Pretzel => {
                let (big_r, r, k) = (self.param("R"), self.param("r"), self.param("blend"));
                self.ring_centres().iter().fold(f64::INFINITY, |d, c| {
                    sdf::smooth_union(d, sdf::torus(p, *c, big_r, |_| r), k)
                })
            }
        }
    }

    /// Bounding box of the solid (before blending, which adds at most `blend / 4`).
    pub fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        let half = match self.kind {
            ShapeKind::Sphere => [self.param("r"); 3],
            ShapeKind::Torus => {
                let (big_r, r) = (self.param("R"), self.param("r"));
                [big_r + r, big_r + r, r]
            }
            ShapeKind::VaryingTorus => {
                let (big_r, r) = (self.param("R"), self.param("r0") * (1.0 + self.param("a")));
                [big_r + r, big_r + r, r]
            }
            ShapeKind::Dumbbell | ShapeKind::Chain => {
                let radius = self.param("radius");
                let last = self.ball_centres().last().map_or(0.0, |c| c[0]);
                [last + radius, radius, radius]
            }
            ShapeKind::Eight | ShapeKind::Pretzel => {
                let (big_r, r) = (self.param("R"), self.param("r"));
                let last = self.ring_centres().last().map_or(0.0, |c| c[0]);
                [last + big_r + r, big_r + r, r]
            }
        };
        (half.map(|h| -h), half)
    }

    /// The necks this shape has, with their lengths and centres where known.
    pub fn expected_necks(&self) -> Vec<ExpectedNeck> {
        let handle = |length, center, note| ExpectedNeck {
            kind: NeckKind::Handle,
            length,
            center,
            note,
        };
        let tunnel = |length, center, note| ExpectedNeck {
            kind: NeckKind::Tunnel,
            length,
            center,
            note,
        };
        match self.kind {
            ShapeKind::Sphere => Vec::new(),
            ShapeKind::Torus => {
                let (big_r, r) = (self.param("R"), self.param("r"));
                vec![
                    handle(
                        Some(2.0 * PI * r),
                        None,
                        "every meridian circle is equally narrow: position degenerate",
                    ),
                    tunnel(
                        Some(2.0 * PI * (big_r - r)),
                        Some([0.0; 3]),
                        "the inner equator is the shortest loop around the hole",
                    ),
                ]
            }
            ShapeKind::VaryingTorus => {
                let (big_r, r0, a) = (self.param("R"), self.param("r0"), self.param("a"));
                vec![
                    handle(
                        Some(2.0 * PI * r0 * (1.0 - a)),
                        Some([-big_r, 0.0, 0.0]),
                        "the thinnest meridian circle, in the symmetry plane y = 0",
                    ),
                    tunnel(
                        None,
                        Some([0.0; 3]),
                        "around the hole; no closed form for its length",
                    ),
                ]
            }
            ShapeKind::Dumbbell | ShapeKind::Chain => {
                let neck = self.param("neck");
                self.ball_centres()
                    .windows(2)
                    .map(|w| {
                        handle(
                            Some(2.0 * PI * neck),
                            Some([(w[0][0] + w[1][0]) / 2.0, 0.0, 0.0]),
                            "circle of the joining cylinder, midway between the balls",
                        )
                    })
                    .collect()
            }
            ShapeKind::Eight | ShapeKind::Pretzel => {
                let (big_r, r) = (self.param("R"), self.param("r"));
                let centres = self.ring_centres();
                let n = centres.len();
                let mut necks = Vec::new();
                for (i, c) in centres.iter().enumerate() {
                    let length = Some(2.0 * PI * r);
                    let note = "meridian circle of a uniform tube, farthest from the junctions";
                    if n == 1 {
                        necks.push(handle(length, None, "a lone ring: position degenerate"));
                    } else if i == 0 {
                        necks.push(handle(length, Some([c[0] - big_r, 0.0, 0.0]), note));
                    } else if i == n - 1 {
                        necks.push(handle(length, Some([c[0] + big_r, 0.0, 0.0]), note));
                    } else {
                        necks.push(handle(length, Some([c[0], big_r, 0.0]), note));
                        necks.push(handle(length, Some([c[0], -big_r, 0.0]), note));
                    }
                }
                for c in &centres {
                    necks.push(tunnel(None, Some(*c), "around the ring's hole"));
                }
                necks
            }
        }
    }

    /// Mesh the shape: marching tetrahedra with `res` cells along the longest side.
    pub fn mesh(&self) -> Result<SurfaceMesh> {
        self.check()?;
        let (lo, hi) = self.bounds();
        let longest = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
        let h = longest / self.param("res");
        let has_blend = self.kind.params().iter().any(|s| s.name == "blend");
        let blend = if has_blend { self.param("blend") } else { 0.0 };
        let pad = 0.25 * blend + 2.0 * h;
        let lo = lo.map(|x| x - pad);
        let hi = hi.map(|x| x + pad);
        Ok(marching::mesh_level_set(&|p| self.sdf(p), lo, hi, h))
    }
}
