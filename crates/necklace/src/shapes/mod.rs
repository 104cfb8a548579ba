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
use crate::mesh::{Side, SurfaceMesh};

/// The generated shapes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ShapeKind {
    /// A ball: genus 0, no neck.
    Sphere,
    /// An ellipsoid: genus 0, no neck.
    Ellipsoid,
    /// A capsule (a cylinder with round ends): genus 0, no neck although every
    /// circle of the cylinder is equally narrow.
    Capsule,
    /// A ball with a tapering cone limb: genus 0, no neck (the limb never bulges).
    Limb,
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
    /// A body ball with satellite balls on necks of different radii: genus 0.
    Satellites,
    /// Ball-and-stick truncated icosahedron: balls on its 60 vertices, sticks on its
    /// 90 edges; genus 31.
    Buckyball,
    /// A ring whose core curve rises and falls like a saddle, (R cos t, R sin t,
    /// bend · cos 2t): genus 1, and no plane through the hole's saddle closes around it.
    BentRing,
    /// A body ball carrying small rings half buried in it, like a mug's handles: genus
    /// `count`, each ring one handle and one tunnel.
    Rings,
    /// A tube round a (p, q) torus knot (a trefoil by default): genus 1; its tunnel loop
    /// runs once along the tube and bounds no disk outside.
    TorusKnot,
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
const ELLIPSOID: &[ParamSpec] = &[
    real("a", 1.0, 1e-6, 1e6, "semi-axis along x"),
    real("b", 0.7, 1e-6, 1e6, "semi-axis along y"),
    real("c", 0.5, 1e-6, 1e6, "semi-axis along z"),
    whole("res", 48.0, 4.0, 1000.0, RES_DOC),
];
const CAPSULE: &[ParamSpec] = &[
    real(
        "length",
        2.0,
        0.0,
        1e6,
        "length of the cylinder between the round ends",
    ),
    real("r", 0.4, 1e-6, 1e6, "radius"),
    whole("res", 64.0, 4.0, 1000.0, RES_DOC),
];
/// The body ball's radius, of the shapes built on one.
const BODY: ParamSpec = real(
    "body",
    1.0,
    1e-6,
    1e6,
    "radius of the body ball, centred at the origin",
);
const LIMB: &[ParamSpec] = &[
    BODY,
    real(
        "base",
        0.5,
        1e-6,
        1e6,
        "radius of the limb's base ball, at the origin (< body)",
    ),
    real(
        "tip",
        0.15,
        1e-6,
        1e6,
        "radius of the limb's tip ball (< base)",
    ),
    real(
        "length",
        2.5,
        1e-6,
        1e6,
        "the tip ball is centred at x = length (> body + tip)",
    ),
    real("blend", 0.1, 0.0, 1e6, BLEND_DOC),
    whole("res", 96.0, 4.0, 1000.0, RES_DOC),
];
const SATELLITES: &[ParamSpec] = &[
    whole(
        "count",
        4.0,
        1.0,
        12.0,
        "number of satellites, evenly around the z axis in the xy-plane",
    ),
    BODY,
    real(
        "satellite",
        0.45,
        1e-6,
        1e6,
        "radius of each satellite ball",
    ),
    real(
        "distance",
        1.9,
        1e-6,
        1e6,
        "distance of the satellite centres from the origin (> body + satellite)",
    ),
    real(
        "neck",
        0.12,
        1e-6,
        1e6,
        "radius of the first satellite's neck (at 0.3 rad from +x)",
    ),
    real(
        "step",
        0.03,
        0.0,
        1e6,
        "each next satellite's neck (counter-clockwise) is this much wider",
    ),
    real("blend", 0.05, 0.0, 1e6, BLEND_DOC),
    whole("res", 128.0, 4.0, 1000.0, RES_DOC),
];
const BUCKYBALL: &[ParamSpec] = &[
    real(
        "edge",
        1.0,
        1e-6,
        1e6,
        "edge length of the truncated icosahedron",
    ),
    real(
        "ball",
        0.25,
        1e-6,
        1e6,
        "radius of the balls on its vertices (< edge/2)",
    ),
    real(
        "stick",
        0.1,
        1e-6,
        1e6,
        "radius of the sticks on its edges (< ball)",
    ),
    real("blend", 0.03, 0.0, 1e6, BLEND_DOC),
    whole("res", 120.0, 4.0, 1000.0, RES_DOC),
];
const BENT_RING: &[ParamSpec] = &[
    real(
        "R",
        1.0,
        1e-6,
        1e6,
        "radius of the core curve's projection on the xy-plane",
    ),
    real("r", 0.15, 1e-6, 1e6, "tube radius (< R / 2)"),
    real(
        "bend",
        0.45,
        -1e6,
        1e6,
        "height of the core curve's rise and fall: z = bend · cos 2t",
    ),
    whole("res", 72.0, 4.0, 1000.0, RES_DOC),
];
const TORUS_KNOT: &[ParamSpec] = &[
    real("R", 1.0, 1e-6, 1e6, "radius of the torus the knot winds on"),
    real(
        "a",
        0.5,
        1e-6,
        1e6,
        "radius of the knot's swing round that torus (< R)",
    ),
    real("r", 0.14, 1e-6, 1e6, "tube radius"),
    whole("p", 2.0, 2.0, 20.0, "turns round the torus's axis"),
    whole(
        "q",
        3.0,
        2.0,
        20.0,
        "turns round the torus's core (coprime to p)",
    ),
    whole("res", 64.0, 4.0, 1000.0, RES_DOC),
];
const RINGS: &[ParamSpec] = &[
    whole(
        "count",
        4.0,
        1.0,
        20.0,
        "number of rings, spread evenly over the ball (a Fibonacci sphere)",
    ),
    BODY,
    real(
        "ring",
        0.4,
        1e-6,
        1e6,
        "radius of each ring's core circle, centred on the ball's surface (< body)",
    ),
    real(
        "wire",
        0.12,
        1e-6,
        1e6,
        "tube radius of the rings (< ring / 2)",
    ),
    real("blend", 0.08, 0.0, 1e6, BLEND_DOC),
    whole("res", 64.0, 4.0, 1000.0, RES_DOC),
];
/// Angle of the first satellite from +x, in radians. Off the lattice axes so that no
/// neck cylinder runs along a lattice direction, where marching tetrahedra's projected
/// vertices can line up on one ruling and fold a sliver over its neighbour.
const SATELLITE_START: f64 = 0.3;
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
    pub const ALL: [ShapeKind; 15] = [
        ShapeKind::Sphere,
        ShapeKind::Ellipsoid,
        ShapeKind::Capsule,
        ShapeKind::Limb,
        ShapeKind::Torus,
        ShapeKind::VaryingTorus,
        ShapeKind::Dumbbell,
        ShapeKind::Chain,
        ShapeKind::Eight,
        ShapeKind::Pretzel,
        ShapeKind::Satellites,
        ShapeKind::Buckyball,
        ShapeKind::BentRing,
        ShapeKind::Rings,
        ShapeKind::TorusKnot,
    ];

    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            ShapeKind::Sphere => "sphere",
            ShapeKind::Ellipsoid => "ellipsoid",
            ShapeKind::Capsule => "capsule",
            ShapeKind::Limb => "limb",
            ShapeKind::Torus => "torus",
            ShapeKind::VaryingTorus => "varying-torus",
            ShapeKind::Dumbbell => "dumbbell",
            ShapeKind::Chain => "chain",
            ShapeKind::Eight => "eight",
            ShapeKind::Pretzel => "pretzel",
            ShapeKind::Satellites => "satellites",
            ShapeKind::Buckyball => "buckyball",
            ShapeKind::BentRing => "bent-ring",
            ShapeKind::Rings => "rings",
            ShapeKind::TorusKnot => "torus-knot",
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
            ShapeKind::Ellipsoid => ELLIPSOID,
            ShapeKind::Capsule => CAPSULE,
            ShapeKind::Limb => LIMB,
            ShapeKind::Torus => TORUS,
            ShapeKind::VaryingTorus => VARYING_TORUS,
            ShapeKind::Dumbbell => DUMBBELL,
            ShapeKind::Chain => CHAIN,
            ShapeKind::Eight => EIGHT,
            ShapeKind::Pretzel => PRETZEL,
            ShapeKind::Satellites => SATELLITES,
            ShapeKind::Buckyball => BUCKYBALL,
            ShapeKind::BentRing => BENT_RING,
            ShapeKind::Rings => RINGS,
            ShapeKind::TorusKnot => TORUS_KNOT,
        }
    }

    /// One sentence: what the shape is and which necks it has.
    pub fn description(self) -> &'static str {
        match self {
            ShapeKind::Sphere => "ball of radius r; genus 0, no neck inside or outside",
            ShapeKind::Ellipsoid => "ellipsoid with semi-axes a, b, c; genus 0, no neck",
            ShapeKind::Capsule => {
                "cylinder of radius r and the given length with round ends; genus 0; no neck: \
                 the cylinder is uniform, nothing bulges beyond it"
            }
            ShapeKind::Limb => {
                "body ball with a round cone limb tapering from base to tip; genus 0; no neck: \
                 the limb thins monotonically, so nothing bulges beyond a narrow part"
            }
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
                "g tori of tube radius r merged in a row; genus g; g handles of length 2πr (one \
                 per ring: at the far side of each end ring, at +y or −y on a middle ring) and \
                 g tunnels (one per hole)"
            }
            ShapeKind::Satellites => {
                "body ball with count satellite balls on necks of radii neck + i step; genus 0; \
                 one handle per neck, length 2π(neck + i step), no tunnel"
            }
            ShapeKind::Buckyball => {
                "balls on the 60 vertices and sticks on the 90 edges of a truncated \
                 icosahedron; genus 31; 90 handles (one per stick, length 2π stick) and 32 \
                 tunnels (one per pentagon or hexagon window)"
            }
            ShapeKind::Rings => {
                "body ball with count rings of core radius ring and tube radius wire, each \
                 centred on the ball's surface with the outward direction in its plane, so that \
                 half of it stands out as an arch; genus count; per ring one handle (a meridian \
                 of the wire, length 2π wire) and one tunnel (through the arch)"
            }
            ShapeKind::BentRing => {
                "tube of radius r around the curve (R cos t, R sin t, bend cos 2t); genus 1; one \
                 handle (a meridian, length 2πr) and one tunnel around the hole, which no plane \
                 through the hole's centre cuts as a closed curve once |bend| > r"
            }
            ShapeKind::TorusKnot => {
                "tube of radius r around the (p, q) torus knot ((R + a cos qt) cos pt, (R + a cos \
                 qt) sin pt, a sin qt); genus 1; one handle (a meridian, length 2πr) and one \
                 tunnel, which runs once along the tube and bounds no disk outside (a Seifert \
                 longitude: it links the core an even number of times, 0 over the integers)"
            }
        }
    }
}

impl fmt::Display for ShapeKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A neck a shape is known to have.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ExpectedNeck {
    /// Inside (a handle: around a narrow part of the solid) or outside (a tunnel:
    /// around a narrow part of the space around it, e.g. a hole); serialized
    /// `"handle"` / `"tunnel"`.
    #[serde(
        serialize_with = "Side::serialize_as_neck",
        deserialize_with = "Side::deserialize_from_neck"
    )]
    pub kind: Side,
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
            ShapeKind::Sphere | ShapeKind::Ellipsoid | ShapeKind::Capsule => Ok(()),
            ShapeKind::Limb if !(p("tip") < p("base") && p("base") < p("body")) => fail(format!(
                "radii must shrink from body = {} to base = {} to tip = {}",
                p("body"),
                p("base"),
                p("tip")
            )),
            ShapeKind::Limb if p("length") <= p("body") + p("tip") => fail(format!(
                "length = {} must exceed body + tip = {} (the tip would lie inside the body)",
                p("length"),
                p("body") + p("tip")
            )),
            ShapeKind::Satellites if p("distance") <= p("body") + p("satellite") => fail(format!(
                "distance = {} must exceed body + satellite = {} (a satellite would touch the body)",
                p("distance"),
                p("body") + p("satellite")
            )),
            ShapeKind::Satellites if self.satellite_necks().last().copied().unwrap_or(0.0)
                >= p("satellite").min(p("body")) =>
            {
                fail(format!(
                    "the widest neck, {}, must be narrower than the balls",
                    self.satellite_necks().last().copied().unwrap_or(0.0)
                ))
            }
            ShapeKind::Satellites
                if p("count") > 1.0
                    && 2.0 * p("distance") * (PI / p("count")).sin() <= 2.0 * p("satellite") =>
            {
                fail(format!(
                    "{} satellites of radius {} overlap at distance {}",
                    p("count"),
                    p("satellite"),
                    p("distance")
                ))
            }
            ShapeKind::Rings if !(p("ring") < p("body") && 2.0 * p("wire") < p("ring")) => {
                fail(format!(
                    "need 2 wire = {} < ring = {} < body = {}",
                    2.0 * p("wire"),
                    p("ring"),
                    p("body")
                ))
            }
            ShapeKind::Rings if self.ring_separation() <= 2.0 * (p("ring") + p("wire") + p("blend")) => {
                fail(format!(
                    "{} rings of radius {} touch on a ball of radius {}",
                    p("count"),
                    p("ring") + p("wire"),
                    p("body")
                ))
            }
            ShapeKind::Buckyball if !(p("stick") < p("ball") && p("ball") < 0.5 * p("edge")) => {
                fail(format!(
                    "need stick = {} < ball = {} < edge/2 = {}",
                    p("stick"),
                    p("ball"),
                    0.5 * p("edge")
                ))
            }
            ShapeKind::TorusKnot if gcd(p("p") as u64, p("q") as u64) != 1 => fail(format!(
                "torus-knot: p = {} and q = {} must be coprime (else the curve closes early)",
                p("p"),
                p("q")
            )),
            ShapeKind::TorusKnot if !(p("a") < p("R") && 2.0 * p("r") < p("a")) => fail(format!(
                "torus-knot: need 2 r = {} < a = {} < R = {}",
                2.0 * p("r"),
                p("a"),
                p("R")
            )),
            ShapeKind::BentRing if p("r") >= 0.5 * p("R") => fail(format!(
                "bent-ring: the tube radius r = {} must be below R / 2 = {}",
                p("r"),
                0.5 * p("R")
            )),
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

    /// The torus knot's core curve at parameter `t` (period 2π).
    pub fn knot_core(&self, t: f64) -> [f64; 3] {
        let (big_r, a) = (self.param("R"), self.param("a"));
        let (p, q) = (self.param("p"), self.param("q"));
        let rho = big_r + a * (q * t).cos();
        [rho * (p * t).cos(), rho * (p * t).sin(), a * (q * t).sin()]
    }

    /// Genus of the surface.
    pub fn genus(&self) -> usize {
        match self.kind {
            ShapeKind::Sphere
            | ShapeKind::Ellipsoid
            | ShapeKind::Capsule
            | ShapeKind::Limb
            | ShapeKind::Dumbbell
            | ShapeKind::Chain
            | ShapeKind::Satellites => 0,
            ShapeKind::Buckyball => 31,
            ShapeKind::Torus
            | ShapeKind::VaryingTorus
            | ShapeKind::BentRing
            | ShapeKind::TorusKnot => 1,
            ShapeKind::Rings => self.param("count") as usize,
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

    /// Neck radii of the satellites, in order around the z axis from +x.
    fn satellite_necks(&self) -> Vec<f64> {
        let n = self.param("count") as usize;
        (0..n)
            .map(|i| self.param("neck") + i as f64 * self.param("step"))
            .collect()
    }

    /// Unit directions of the satellites, evenly around the z axis from the angle
    /// [`SATELLITE_START`] off +x.
    fn satellite_directions(&self) -> Vec<[f64; 3]> {
        let n = self.param("count") as usize;
        (0..n)
            .map(|i| {
                let a = SATELLITE_START + 2.0 * PI * i as f64 / n as f64;
                [a.cos(), a.sin(), 0.0]
            })
            .collect()
    }

    /// The rings' frames: the unit direction of each ring's centre from the origin (a
    /// Fibonacci sphere) and the unit axis of its circle (perpendicular to it).
    fn ring_frames(&self) -> Vec<([f64; 3], [f64; 3])> {
        let n = self.param("count") as usize;
        let golden = PI * (3.0 - 5f64.sqrt());
        (0..n)
            .map(|i| {
                let z = 1.0 - (2.0 * i as f64 + 1.0) / n as f64;
                let r = (1.0 - z * z).max(0.0).sqrt();
                let phi = golden * i as f64 + SATELLITE_START;
                let d = [r * phi.cos(), r * phi.sin(), z];
                let other = if z.abs() > 0.9 {
                    [1.0, 0.0, 0.0]
                } else {
                    [0.0, 0.0, 1.0]
                };
                let a = [
                    d[1] * other[2] - d[2] * other[1],
                    d[2] * other[0] - d[0] * other[2],
                    d[0] * other[1] - d[1] * other[0],
                ];
                (d, scale3(a, 1.0 / dist3(a, [0.0; 3])))
            })
            .collect()
    }

    /// The shortest distance between two ring centres (infinite for one ring).
    fn ring_separation(&self) -> f64 {
        let body = self.param("body");
        let frames = self.ring_frames();
        let mut least = f64::INFINITY;
        for (i, (a, _)) in frames.iter().enumerate() {
            for (b, _) in &frames[i + 1..] {
                least = least.min(body * dist3(*a, *b));
            }
        }
        least
    }

    /// The signed distance function (negative inside).
    pub fn sdf(&self, p: [f64; 3]) -> f64 {
        let o = [0.0; 3];
        match self.kind {
            ShapeKind::Sphere => sdf::ball(p, o, self.param("r")),
            ShapeKind::Ellipsoid => {
                sdf::ellipsoid(p, [self.param("a"), self.param("b"), self.param("c")])
            }
            ShapeKind::Capsule => {
                let half = 0.5 * self.param("length");
                sdf::capsule(p, [-half, 0.0, 0.0], [half, 0.0, 0.0], self.param("r"))
            }
            ShapeKind::Limb => {
                let tip = [self.param("length"), 0.0, 0.0];
                let cone = sdf::round_cone(p, o, tip, self.param("base"), self.param("tip"));
                sdf::smooth_union(
                    sdf::ball(p, o, self.param("body")),
                    cone,
                    self.param("blend"),
                )
            }
            ShapeKind::Satellites => {
                let (k, dist, sat) = (
                    self.param("blend"),
                    self.param("distance"),
                    self.param("satellite"),
                );
                let mut d = sdf::ball(p, o, self.param("body"));
                for (dir, neck) in self
                    .satellite_directions()
                    .iter()
                    .zip(self.satellite_necks())
                {
                    let c = scale3(*dir, dist);
                    d = sdf::smooth_union(d, sdf::capsule(p, o, c, neck), k);
                    d = sdf::smooth_union(d, sdf::ball(p, c, sat), k);
                }
                d
            }
            ShapeKind::Buckyball => {
                // In units of the edge length, where the skeleton is computed once.
                let e = self.param("edge");
                let (ball, stick, k) = (
                    self.param("ball") / e,
                    self.param("stick") / e,
                    self.param("blend") / e,
                );
                let p = scale3(p, 1.0 / e);
                let (vertices, edges) = unit_truncated_icosahedron();
                // Only parts within reach can change the value: skip the rest.
                let reach = 1.0 + ball + k;
                let near: Vec<bool> = vertices.iter().map(|v| dist3(p, *v) < reach).collect();
                let mut d = f64::INFINITY;
                for (v, _) in vertices.iter().zip(&near).filter(|(_, n)| **n) {
                    d = sdf::smooth_union(d, sdf::ball(p, *v, ball), k);
                }
                for [a, b] in edges.iter().filter(|[a, b]| near[*a] || near[*b]) {
                    d = sdf::smooth_union(d, sdf::capsule(p, vertices[*a], vertices[*b], stick), k);
                }
                let d = if d.is_finite() {
                    d
                } else {
                    // Far from every part: the distance to the nearest ball bounds it.
                    vertices
                        .iter()
                        .map(|v| sdf::ball(p, *v, ball))
                        .fold(f64::INFINITY, f64::min)
                };
                d * e
            }
            ShapeKind::Torus => {
                let r = self.param("r");
                sdf::torus(p, o, self.param("R"), |_| r)
            }
            ShapeKind::Rings => {
                let (body, ring, wire) =
                    (self.param("body"), self.param("ring"), self.param("wire"));
                let mut d = sdf::ball(p, o, body);
                for (dir, axis) in self.ring_frames() {
                    // The ring's frame: x along the outward direction, z along its axis.
                    let q = [0, 1, 2].map(|k| p[k] - body * dir[k]);
                    let y = [
                        axis[1] * dir[2] - axis[2] * dir[1],
                        axis[2] * dir[0] - axis[0] * dir[2],
                        axis[0] * dir[1] - axis[1] * dir[0],
                    ];
                    let dot = |u: [f64; 3]| u[0] * q[0] + u[1] * q[1] + u[2] * q[2];
                    let local = [dot(dir), dot(y), dot(axis)];
                    d = sdf::smooth_union(
                        d,
                        sdf::torus(local, o, ring, |_| wire),
                        self.param("blend"),
                    );
                }
                d
            }
            ShapeKind::TorusKnot => {
                sdf::distance_to_closed_curve(p, |t| self.knot_core(t)) - self.param("r")
            }
            ShapeKind::BentRing => {
                let (big_r, bend) = (self.param("R"), self.param("bend"));
                let core = |t: f64| [big_r * t.cos(), big_r * t.sin(), bend * (2.0 * t).cos()];
                sdf::distance_to_closed_curve(p, core) - self.param("r")
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
            ShapeKind::Ellipsoid => [self.param("a"), self.param("b"), self.param("c")],
            ShapeKind::Capsule => {
                let r = self.param("r");
                [0.5 * self.param("length") + r, r, r]
            }
            ShapeKind::Limb => {
                let body = self.param("body");
                let x = body.max(self.param("length") + self.param("tip"));
                // Symmetric in x so the shape stays centred on the box's middle.
                [x, body, body]
            }
            ShapeKind::Satellites => {
                let xy = self.param("distance") + self.param("satellite");
                [xy, xy, self.param("body")]
            }
            ShapeKind::Buckyball => {
                let (vertices, _) = unit_truncated_icosahedron();
                let r = vertices
                    .iter()
                    .map(|v| dist3(*v, [0.0; 3]))
                    .fold(0.0, f64::max);
                [r * self.param("edge") + self.param("ball"); 3]
            }
            ShapeKind::Torus => {
                let (big_r, r) = (self.param("R"), self.param("r"));
                [big_r + r, big_r + r, r]
            }
            ShapeKind::VaryingTorus => {
                let (big_r, r) = (self.param("R"), self.param("r0") * (1.0 + self.param("a")));
                [big_r + r, big_r + r, r]
            }
            ShapeKind::BentRing => {
                let (big_r, r) = (self.param("R"), self.param("r"));
                [big_r + r, big_r + r, self.param("bend").abs() + r]
            }
            ShapeKind::TorusKnot => {
                let (big_r, a, r) = (self.param("R"), self.param("a"), self.param("r"));
                [big_r + a + r, big_r + a + r, a + r]
            }
            ShapeKind::Rings => [self.param("body") + self.param("ring") + self.param("wire"); 3],
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
            kind: Side::Inside,
            length,
            center,
            note,
        };
        let tunnel = |length, center, note| ExpectedNeck {
            kind: Side::Outside,
            length,
            center,
            note,
        };
        match self.kind {
            ShapeKind::Sphere | ShapeKind::Ellipsoid | ShapeKind::Capsule | ShapeKind::Limb => {
                Vec::new()
            }
            ShapeKind::Satellites => {
                let (body, dist, sat) = (
                    self.param("body"),
                    self.param("distance"),
                    self.param("satellite"),
                );
                let mid = 0.5 * (body + dist - sat);
                self.satellite_directions()
                    .iter()
                    .zip(self.satellite_necks())
                    .map(|(dir, neck)| {
                        handle(
                            Some(2.0 * PI * neck),
                            Some(scale3(*dir, mid)),
                            "circle of the satellite's neck, between body and satellite",
                        )
                    })
                    .collect()
            }
            ShapeKind::Buckyball => {
                let (vertices, edges) = unit_truncated_icosahedron();
                let (e, stick) = (self.param("edge"), self.param("stick"));
                let mut necks: Vec<ExpectedNeck> = edges
                    .iter()
                    .map(|[a, b]| {
                        let (a, b) = (vertices[*a], vertices[*b]);
                        handle(
                            Some(2.0 * PI * stick),
                            Some([0, 1, 2].map(|k| 0.5 * e * (a[k] + b[k]))),
                            "circle of a stick, midway between its balls",
                        )
                    })
                    .collect();
                necks.extend(
                    (0..32).map(|_| tunnel(None, None, "around a pentagon or hexagon window")),
                );
                necks
            }
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
            ShapeKind::Rings => {
                let (body, ring, wire) =
                    (self.param("body"), self.param("ring"), self.param("wire"));
                let mut necks = Vec::new();
                for (dir, _) in self.ring_frames() {
                    necks.push(handle(
                        Some(2.0 * PI * wire),
                        None,
                        "a meridian circle of the ring's uniform wire: position degenerate",
                    ));
                    necks.push(tunnel(
                        None,
                        Some(scale3(dir, body + 0.5 * (ring - wire))),
                        "through the arch, between the ring and the ball; no closed form",
                    ));
                }
                necks
            }
            ShapeKind::TorusKnot => vec![
                handle(
                    Some(2.0 * PI * self.param("r")),
                    None,
                    "a meridian circle of the uniform tube: position degenerate",
                ),
                tunnel(
                    None,
                    None,
                    "runs once along the tube and bounds no disk outside (the linked search); \
                     no closed form",
                ),
            ],
            ShapeKind::BentRing => vec![
                handle(
                    Some(2.0 * PI * self.param("r")),
                    None,
                    "a meridian circle of the uniform tube: position degenerate",
                ),
                tunnel(
                    None,
                    Some([0.0; 3]),
                    "around the hole, rising and falling with the ring; no closed form",
                ),
            ],
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
                        let note = "meridian circle at +y or −y: the two are the same cycle";
                        necks.push(handle(length, None, note));
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

fn scale3(v: [f64; 3], s: f64) -> [f64; 3] {
    v.map(|x| x * s)
}

fn dist3(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Vertices and edges of a polyhedron.
type Skeleton = (Vec<[f64; 3]>, Vec<[usize; 2]>);

/// [`truncated_icosahedron`] with unit edges, computed once.
fn unit_truncated_icosahedron() -> &'static Skeleton {
    static SKELETON: std::sync::OnceLock<Skeleton> = std::sync::OnceLock::new();
    SKELETON.get_or_init(|| truncated_icosahedron(1.0))
}

/// The 60 vertices and 90 edges of a truncated icosahedron with the given edge length,
/// centred at the origin.
///
/// With golden ratio φ and edge length 2, the vertices are the even permutations of
/// (0, ±1, ±3φ), (±1, ±(2 + φ), ±2φ) and (±φ, ±2, ±φ³) (φ³ = 2φ + 1); the edges join
/// the vertex pairs at distance 2.
fn truncated_icosahedron(edge: f64) -> Skeleton {
    let phi = (1.0 + 5f64.sqrt()) / 2.0;
    let s = 0.5 * edge;
    let mut vertices = Vec::with_capacity(60);
    for base in [
        [0.0, 1.0, 3.0 * phi],
        [1.0, 2.0 + phi, 2.0 * phi],
        [phi, 2.0, 2.0 * phi + 1.0],
    ] {
        for signs in 0..8 {
            let v: [f64; 3] = std::array::from_fn(|k| {
                if signs & (1 << k) != 0 {
                    -base[k]
                } else {
                    base[k]
                }
            });
            // A sign flip of a zero coordinate gives the same point.
            if (0..3).any(|k| base[k] == 0.0 && signs & (1 << k) != 0) {
                continue;
            }
            for shift in 0..3 {
                vertices.push([v[shift] * s, v[(shift + 1) % 3] * s, v[(shift + 2) % 3] * s]);
            }
        }
    }
    let mut edges = Vec::with_capacity(90);
    for i in 0..vertices.len() {
        for j in i + 1..vertices.len() {
            if (dist3(vertices[i], vertices[j]) - edge).abs() < 1e-6 * edge {
                edges.push([i, j]);
            }
        }
    }
    (vertices, edges)
}

/// Greatest common divisor.
fn gcd(a: u64, b: u64) -> u64 {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_truncated_icosahedron_has_60_vertices_90_edges_and_degree_3() {
        let (vertices, edges) = truncated_icosahedron(1.0);
        assert_eq!((vertices.len(), edges.len()), (60, 90));
        let mut degree = [0; 60];
        for [a, b] in &edges {
            degree[*a] += 1;
            degree[*b] += 1;
        }
        assert!(degree.iter().all(|d| *d == 3));
        // Circumradius of the unit-edge truncated icosahedron: √(58 + 18√5) / 4.
        let r = (58.0 + 18.0 * 5f64.sqrt()).sqrt() / 4.0;
        assert!(vertices
            .iter()
            .all(|v| (dist3(*v, [0.0; 3]) - r).abs() < 1e-12));
    }
}
