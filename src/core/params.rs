//! Every tunable number of the method in one table ([`PARAMETERS`]): name, kind, range, unit,
//! group and help. Parsing, validation, the command line's `--help`, the C API's option table,
//! `docs/c-api.md` and the QGIS dialog are all derived from it, so they cannot disagree. The
//! defaults live once, in [`Params::default`].
//!
//! Lengths are in cells (the unit-cell frame of method.md §0), so the defaults hold for data in
//! metres, feet or degrees alike.

use serde::Serialize;
use std::fmt::Write;

/// How the Snake turns centroid forces into loads (method.md §4, "known weakness").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum LoadModel {
    /// The paper's element loads (h/2·f, h²/12·f): long edges pull harder.
    Element,
    /// The force is applied at its node only, so crowded regions with short edges move as much as
    /// large ones.
    Nodal,
}

/// The shape of the cells (method.md §6, §10).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum CellShape {
    Square,
    Hex,
}

/// Which way hexagonal cells point (method.md §10).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum HexOrientation {
    /// A vertex at the top: rows of hexagons, every other row offset half a cell sideways.
    Pointy,
    /// An edge at the top: columns of hexagons, every other column offset half a cell down.
    Flat,
}

/// The parameters of one run. `Params::default()` is what every face uses; [`PARAMETERS`]
/// describes each field.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Params {
    pub alpha: f64,
    pub beta: f64,
    pub force_cap: f64,
    pub max_steps: usize,
    pub epsilon: f64,
    pub step_ratio: f64,
    pub spring: f64,
    pub stop_on_no_progress: bool,
    pub load_model: LoadModel,
    pub vertices_per_region: f64,
    pub simplify_tolerance: Option<f64>,
    pub point_adjacency: bool,
    pub cell: CellShape,
    pub hex_orientation: HexOrientation,
    pub island_limit: f64,
    pub group_gap: usize,
    pub shifts: Vec<[f64; 2]>,
    pub noise_levels: Vec<f64>,
    /// Most candidate layouts; `None`: [`Params::layout_count`] decides by the number of
    /// regions.
    pub max_layouts: Option<usize>,
    /// Most candidate layouts refined; `None`: [`Params::refined_count`] decides by the number
    /// of regions.
    pub max_refined: Option<usize>,
    pub seed: u64,
    pub refine: bool,
    pub refine_moves_per_region: usize,
    pub refine_temperature: f64,
    pub refine_w_adjacent: f64,
    pub refine_w_angle: f64,
    pub refine_w_misdirected: f64,
    pub refine_w_location: f64,
    pub refine_location_knee: f64,
    pub refine_location_far: f64,
    pub refine_w_far: f64,
    pub refine_w_landmass: f64,
    pub refine_w_notch: f64,
    pub refine_cell_ratio: f64,
    pub refine_swap_only_below: usize,
    pub topsis_weights: [f64; 4],
    pub threads: usize,
}

impl Default for Params {
    fn default() -> Self {
        Params {
            alpha: 1.0,
            beta: 1.0,
            force_cap: 0.1,
            max_steps: 30,
            epsilon: 1e-3,
            step_ratio: 5.0,
            spring: 1e-2,
            stop_on_no_progress: false,
            load_model: LoadModel::Nodal,
            vertices_per_region: 2.0,
            simplify_tolerance: None,
            point_adjacency: false,
            cell: CellShape::Square,
            hex_orientation: HexOrientation::Pointy,
            island_limit: 5.0,
            group_gap: 0,
            // A 3×3 set: the lattice's position matters as much as the Snake's noise (measured
            // on the shared layers, 9 shifts found one-piece layouts 4 did not).
            shifts: [0.0, 0.33, 0.67]
                .iter()
                .flat_map(|&x| [0.0, 0.33, 0.67].map(|y| [x, y]))
                .collect(),
            noise_levels: vec![0.02, 0.04],
            max_layouts: None,
            max_refined: None,
            seed: 0,
            refine: true,
            refine_moves_per_region: 800,
            refine_temperature: 0.5,
            refine_w_adjacent: 1.0,
            refine_w_angle: 1.0,
            refine_w_misdirected: 0.5,
            refine_w_location: 0.25,
            // Linear beyond a cell, as §8 measures location: the square pulled the regions of a
            // layer of uneven density (us_counties) towards their far places, out of the
            // lattice's interior, and left inlets a cell wide (BENCHMARKS.md, "Location cost").
            refine_location_knee: 1.0,
            refine_location_far: 3.0,
            refine_w_far: 0.0,
            refine_w_landmass: 2.0,
            refine_w_notch: 1.0,
            refine_cell_ratio: 1.3,
            refine_swap_only_below: 20,
            topsis_weights: [1.0; 4],
            threads: 0,
        }
    }
}

/// Which step of the method a parameter belongs to, in the order of the method.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Group {
    Snake,
    Outline,
    Cells,
    Groups,
    Candidates,
    Refinement,
    Ranking,
    Run,
}

impl Group {
    pub fn as_str(self) -> &'static str {
        match self {
            Group::Snake => "Snake",
            Group::Outline => "Outline",
            Group::Cells => "Cells",
            Group::Groups => "Groups",
            Group::Candidates => "Candidates",
            Group::Refinement => "Refinement",
            Group::Ranking => "Ranking",
            Group::Run => "Run",
        }
    }

    /// What the group is, for headings.
    pub fn title(self) -> &'static str {
        match self {
            Group::Snake => {
                "Snake: the beam network that moves centroids and outline (method.md §3–5)"
            }
            Group::Outline => "Outline and adjacency (method.md §1)",
            Group::Cells => "Cells: squares or hexagons (method.md §6, §10)",
            Group::Groups => "Groups kept together (method.md §10; with a group field)",
            Group::Candidates => "Candidate layouts (method.md §7)",
            Group::Refinement => "Refinement after the assignment (method.md §6b)",
            Group::Ranking => "Ranking of the candidates (method.md §7)",
            Group::Run => "Running (no effect on the result)",
        }
    }
}

/// What values a parameter takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// A finite number.
    Real,
    /// A whole number of `bits` bits, unsigned.
    Integer { bits: u32 },
    /// `true` or `false`.
    Bool,
    /// One of the names.
    Choice(&'static [&'static str]),
    /// Comma-separated numbers, each in the range, `min..=max` of them.
    RealList { min: usize, max: usize },
    /// Comma-separated `x:y` pairs, each number in the range, `min..=max` of them.
    PairList { min: usize, max: usize },
}

impl Kind {
    pub fn as_str(self) -> &'static str {
        match self {
            Kind::Real => "real",
            Kind::Integer { .. } => "integer",
            Kind::Bool => "bool",
            Kind::Choice(_) => "choice",
            Kind::RealList { .. } => "real list",
            Kind::PairList { .. } => "pair list",
        }
    }
}

/// One end of a range.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bound {
    pub value: f64,
    /// The end itself is excluded.
    pub open: bool,
}

const fn closed(value: f64) -> Option<Bound> {
    Some(Bound { value, open: false })
}

const fn open(value: f64) -> Option<Bound> {
    Some(Bound { value, open: true })
}

/// A parameter's value, of its [`Kind`].
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    Real(f64),
    Integer(u64),
    Bool(bool),
    Choice(&'static str),
    Reals(Vec<f64>),
    Pairs(Vec<[f64; 2]>),
    /// An optional parameter left unset.
    Unset,
}

impl Value {
    /// The value as text that [`Params::set`] reads back (the default shown in every face).
    pub fn to_text(&self) -> String {
        let number = |v: f64| format!("{v}");
        match self {
            Value::Real(v) => number(*v),
            Value::Integer(v) => v.to_string(),
            Value::Bool(v) => v.to_string(),
            Value::Choice(v) => (*v).to_owned(),
            Value::Reals(v) => v.iter().map(|&x| number(x)).collect::<Vec<_>>().join(","),
            Value::Pairs(v) => v
                .iter()
                .map(|[x, y]| format!("{}:{}", number(*x), number(*y)))
                .collect::<Vec<_>>()
                .join(","),
            Value::Unset => "none".to_owned(),
        }
    }
}

/// One row of the parameter table.
pub struct Parameter {
    pub name: &'static str,
    pub kind: Kind,
    /// It may be left unset (`none`).
    pub optional: bool,
    /// The range of the value (of each element for lists); `None`: unbounded on that side.
    pub min: Option<Bound>,
    pub max: Option<Bound>,
    /// Unit of the value ("cells", "cells²", "°", ""); lengths are in cells (§0).
    pub unit: &'static str,
    pub group: Group,
    /// Best left alone by most users (QGIS shows it under "Advanced").
    pub advanced: bool,
    /// One line, for lists and tooltips.
    pub summary: &'static str,
    /// What it does and when to change it.
    pub help: &'static str,
    access: Accessors,
}

/// Reading and writing a parameter's field of [`Params`].
type Accessors = (fn(&Params) -> Value, fn(&mut Params, Value));

impl Parameter {
    /// The parameter's value in `params`.
    pub fn value(&self, params: &Params) -> Value {
        (self.access.0)(params)
    }

    /// Its default, as text.
    pub fn default_text(&self) -> String {
        self.value(&Params::default()).to_text()
    }

    /// The range as mathematicians write it, e.g. "(0, 1]", "[1, ∞)"; for lists, of each element.
    pub fn range_text(&self) -> String {
        match self.kind {
            Kind::Bool => return "true or false".into(),
            Kind::Choice(names) => return names.join(" or "),
            _ => {}
        }
        let lower = match self.min {
            Some(b) => format!("{}{}", if b.open { "(" } else { "[" }, b.value),
            None => "(-∞".into(),
        };
        let upper = match (self.max, self.kind) {
            (Some(b), _) => format!("{}{}", b.value, if b.open { ")" } else { "]" }),
            (None, Kind::Integer { bits }) => format!("2^{bits} - 1]"),
            (None, _) => "∞)".into(),
        };
        let range = format!("{lower}, {upper}");
        match self.kind {
            Kind::RealList { min, max } | Kind::PairList { min, max } => {
                let count = if min == max {
                    format!("{min}")
                } else {
                    format!("{min} to {max}")
                };
                let items = if matches!(self.kind, Kind::PairList { .. }) {
                    "x:y pairs"
                } else {
                    "numbers"
                };
                format!("{count} {items}, each in {range}")
            }
            _ => range,
        }
    }

    /// Whether `v` lies in the range.
    fn admits(&self, v: f64) -> bool {
        let above = self
            .min
            .is_none_or(|b| if b.open { v > b.value } else { v >= b.value });
        let below = self
            .max
            .is_none_or(|b| if b.open { v < b.value } else { v <= b.value });
        v.is_finite() && above && below
    }

    /// Checks `value` against the kind and the range; the message names the parameter.
    fn check(&self, value: &Value) -> Result<(), String> {
        let name = self.name;
        let out_of_range =
            |v: String| format!("parameter {name} must be in {}, got {v}", self.range_text());
        match value {
            Value::Unset if self.optional => Ok(()),
            Value::Unset => Err(format!("parameter {name} cannot be none")),
            // Debug prints the shortest text that reads back as the value: 1e308, not 309 digits.
            Value::Real(v) if !self.admits(*v) => Err(out_of_range(format!("{v:?}"))),
            Value::Integer(v) if !self.admits(*v as f64) => Err(out_of_range(v.to_string())),
            Value::Reals(items) => self.check_list(items.iter().copied(), items.len()),
            Value::Pairs(items) => {
                self.check_list(items.iter().flat_map(|p| p.iter().copied()), items.len())
            }
            _ => Ok(()),
        }
    }

    fn check_list(&self, items: impl Iterator<Item = f64>, count: usize) -> Result<(), String> {
        let name = self.name;
        if let Kind::RealList { min, max } | Kind::PairList { min, max } = self.kind {
            if !(min..=max).contains(&count) {
                return Err(format!(
                    "parameter {name} takes {}, got {count}",
                    self.range_text()
                ));
            }
        }
        for v in items {
            if !self.admits(v) {
                return Err(format!(
                    "parameter {name}: each value must be in {}, got {v:?}",
                    self.range_text()
                        .rsplit("each in ")
                        .next()
                        .unwrap_or_default()
                ));
            }
        }
        Ok(())
    }

    /// Reads `text` as a value of this parameter's kind (not yet range-checked).
    fn parse(&self, text: &str) -> Result<Value, String> {
        let name = self.name;
        let text = text.trim();
        let bad = |what: &str| format!("parameter {name}: {what}, got {text:?}");
        let number = |part: &str| -> Result<f64, String> {
            let v: f64 = part.trim().parse().map_err(|_| bad("expected a number"))?;
            if v.is_finite() {
                Ok(v)
            } else {
                Err(bad("expected a finite number"))
            }
        };
        if self.optional && text.eq_ignore_ascii_case("none") {
            return Ok(Value::Unset);
        }
        Ok(match self.kind {
            Kind::Real => Value::Real(number(text)?),
            Kind::Integer { bits } => {
                // A whole-number real (12.0) is accepted too: hosts often hold numbers as doubles.
                let whole = |t: &str| {
                    t.parse::<u64>().ok().or_else(|| {
                        let v: f64 = t.parse().ok()?;
                        (v >= 0.0 && v.fract() == 0.0 && v < 2f64.powi(64)).then_some(v as u64)
                    })
                };
                let v = whole(text).ok_or_else(|| bad("expected a whole number >= 0"))?;
                if bits < 64 && v >> bits != 0 {
                    return Err(bad(&format!("expected a whole number below 2^{bits}")));
                }
                Value::Integer(v)
            }
            Kind::Bool => Value::Bool(match text.to_ascii_lowercase().as_str() {
                "true" | "yes" | "on" | "1" => true,
                "false" | "no" | "off" | "0" => false,
                _ => return Err(bad("expected true or false")),
            }),
            Kind::Choice(names) => Value::Choice(
                names
                    .iter()
                    .find(|n| n.eq_ignore_ascii_case(text))
                    .ok_or_else(|| bad(&format!("expected {}", names.join(" or "))))?,
            ),
            Kind::RealList { .. } if text.is_empty() => Value::Reals(Vec::new()),
            Kind::RealList { .. } => {
                Value::Reals(text.split(',').map(number).collect::<Result<_, _>>()?)
            }
            Kind::PairList { .. } => Value::Pairs(
                text.split(',')
                    .map(|pair| {
                        let (x, y) = pair
                            .split_once(':')
                            .ok_or_else(|| bad("expected x:y pairs"))?;
                        Ok([number(x)?, number(y)?])
                    })
                    .collect::<Result<_, String>>()?,
            ),
        })
    }
}

/// Shorthand for the table's accessors: `accessors!(name, Variant)` reads and writes `Params::name`
/// as `Value::Variant`.
macro_rules! accessors {
    ($field:ident, Integer) => {
        (
            |p| Value::Integer(p.$field as u64),
            |p, v| {
                if let Value::Integer(v) = v {
                    // The range check has kept the value within the field's type.
                    p.$field = v.try_into().unwrap_or_default()
                }
            },
        )
    };
    // An optional count: none is `None`.
    ($field:ident, OptionalInteger) => {
        (
            |p| p.$field.map_or(Value::Unset, |v| Value::Integer(v as u64)),
            |p, v| {
                p.$field = match v {
                    // The range check has kept the value within the field's type.
                    Value::Integer(v) => v.try_into().ok(),
                    _ => None,
                }
            },
        )
    };
    ($field:ident, $variant:ident) => {
        (
            |p| Value::$variant(Clone::clone(&p.$field)),
            |p, v| {
                if let Value::$variant(v) = v {
                    p.$field = v
                }
            },
        )
    };
}

/// The accessors of a choice parameter whose field is an enum: each name with its variant.
macro_rules! choice_accessors {
    ($field:ident, $($name:literal => $variant:path),+ $(,)?) => {
        (
            |p| Value::Choice(match p.$field { $($variant => $name,)+ }),
            |p, v| {
                if let Value::Choice(name) = v {
                    $(if name == $name {
                        p.$field = $variant;
                    })+
                }
            },
        )
    };
}

/// Every parameter, grouped by the step of the method it belongs to, in the method's order.
///
/// The ranges of α, β and κ are those over which every corner of the box lays out the shared
/// us_states layer and a 2,000-region Voronoi layer (tests/properties.rs checks it); wider values
/// make the stiffness matrix numerically singular.
pub static PARAMETERS: &[Parameter] = &[
    Parameter {
        name: "alpha",
        kind: Kind::Real,
        optional: false,
        min: closed(1e-3),
        max: closed(1e3),
        unit: "",
        group: Group::Snake,
        advanced: false,
        summary: "Beam elasticity α (resistance to stretching)",
        help: "How strongly each network edge resists a change of length. Only the ratio α:β \
             matters to the shape of a step; raise α to keep distances, raise β to keep the \
             outline smooth.",
        access: accessors!(alpha, Real),
    },
    Parameter {
        name: "beta",
        kind: Kind::Real,
        optional: false,
        min: closed(1e-3),
        max: closed(1e3),
        unit: "",
        group: Group::Snake,
        advanced: false,
        summary: "Beam rigidity β (resistance to bending)",
        help: "How strongly each network edge resists bending: higher values move neighbouring \
             nodes more alike.",
        access: accessors!(beta, Real),
    },
    Parameter {
        name: "force_cap",
        kind: Kind::Real,
        optional: false,
        min: open(0.0),
        max: closed(1.0),
        unit: "cells",
        group: Group::Snake,
        advanced: false,
        summary: "Force cap T_f (Eq. 7)",
        help: "The largest force on a centroid in one step; all forces are scaled so the largest \
             is at most this.",
        access: accessors!(force_cap, Real),
    },
    Parameter {
        name: "max_steps",
        kind: Kind::Integer { bits: 32 },
        optional: false,
        min: closed(0.0),
        max: closed(10_000.0),
        unit: "steps",
        group: Group::Snake,
        advanced: false,
        summary: "Most Snake steps T_s",
        help: "The Snake stops after this many steps at the latest; 0 switches it off (the \
             centroids stay where they are).",
        access: accessors!(max_steps, Integer),
    },
    Parameter {
        name: "epsilon",
        kind: Kind::Real,
        optional: false,
        min: open(0.0),
        max: closed(1.0),
        unit: "cells",
        group: Group::Snake,
        advanced: true,
        summary: "Convergence threshold ε",
        help: "The Snake stops when no node moves more than this in a step.",
        access: accessors!(epsilon, Real),
    },
    Parameter {
        name: "step_ratio",
        kind: Kind::Real,
        optional: false,
        min: closed(1.0),
        max: closed(100.0),
        unit: "",
        group: Group::Snake,
        advanced: true,
        summary: "Step ratio R",
        help: "No node moves more than R times the largest force in one step.",
        access: accessors!(step_ratio, Real),
    },
    Parameter {
        name: "spring",
        kind: Kind::Real,
        optional: false,
        min: closed(1e-4),
        max: closed(1.0),
        unit: "",
        group: Group::Snake,
        advanced: true,
        summary: "Weak spring κ, as a fraction of the mean stiffness",
        help: "Anchors every node to where it is, so the stiffness matrix is definite without \
             pinning a node; below about 1e-3 the whole network drifts.",
        access: accessors!(spring, Real),
    },
    Parameter {
        name: "stop_on_no_progress",
        kind: Kind::Bool,
        optional: false,
        min: None,
        max: None,
        unit: "",
        group: Group::Snake,
        advanced: true,
        summary: "Stop when the forces stall",
        help: "Stop the Snake when the largest force has not fallen for 3 steps (method.md §5, \
             condition 2).",
        access: accessors!(stop_on_no_progress, Bool),
    },
    Parameter {
        name: "load_model",
        kind: Kind::Choice(&["nodal", "element"]),
        optional: false,
        min: None,
        max: None,
        unit: "",
        group: Group::Snake,
        advanced: true,
        summary: "How forces become loads",
        help:
            "nodal: each centroid's force at its own node, so small crowded regions move as much \
             as large ones; element: the paper's loads along the edges (long edges pull harder).",
        access: choice_accessors!(
            load_model,
            "nodal" => LoadModel::Nodal,
            "element" => LoadModel::Element,
        ),
    },
    Parameter {
        name: "vertices_per_region",
        kind: Kind::Real,
        optional: false,
        min: closed(0.1),
        max: closed(1000.0),
        unit: "",
        group: Group::Outline,
        advanced: true,
        summary: "Outline vertices kept per region",
        help: "The map outline is simplified to about this many vertices per region before it \
             joins the network (the paper's ratio of 0.5 centroids per boundary node is 2).",
        access: accessors!(vertices_per_region, Real),
    },
    Parameter {
        name: "simplify_tolerance",
        kind: Kind::Real,
        optional: true,
        min: closed(0.0),
        max: closed(100.0),
        unit: "cells²",
        group: Group::Outline,
        advanced: true,
        summary: "Outline simplification tolerance",
        help: "Visvalingam area tolerance of the outline simplification; when given, it \
             overrides vertices_per_region. none: from vertices_per_region.",
        access: (
            |p| p.simplify_tolerance.map_or(Value::Unset, Value::Real),
            |p, v| {
                p.simplify_tolerance = match v {
                    Value::Real(v) => Some(v),
                    _ => None,
                }
            },
        ),
    },
    Parameter {
        name: "point_adjacency",
        kind: Kind::Bool,
        optional: false,
        min: None,
        max: None,
        unit: "",
        group: Group::Outline,
        advanced: false,
        summary: "Regions touching at a point are neighbours",
        help: "Queen adjacency (a shared point is enough) instead of rook (a shared border line).",
        access: accessors!(point_adjacency, Bool),
    },
    Parameter {
        name: "cell",
        kind: Kind::Choice(&["square", "hex"]),
        optional: false,
        min: None,
        max: None,
        unit: "",
        group: Group::Cells,
        advanced: false,
        summary: "Cell shape",
        help: "square: a square lattice, 8 neighbours (edge or corner); hex: hexagons of the same \
             area, 6 neighbours, all sharing an edge (see hex_orientation).",
        access: choice_accessors!(cell, "square" => CellShape::Square, "hex" => CellShape::Hex),
    },
    Parameter {
        name: "hex_orientation",
        kind: Kind::Choice(&["pointy", "flat"]),
        optional: false,
        min: None,
        max: None,
        unit: "",
        group: Group::Cells,
        advanced: false,
        summary: "Hexagons pointy- or flat-topped",
        help: "pointy: a vertex at the top, rows of hexagons with every other row offset half a \
             cell to the right; flat: an edge at the top, columns with every other column offset \
             half a cell down. Only used with cell hex.",
        access: choice_accessors!(
            hex_orientation,
            "pointy" => HexOrientation::Pointy,
            "flat" => HexOrientation::Flat,
        ),
    },
    Parameter {
        name: "island_limit",
        kind: Kind::Real,
        optional: false,
        min: closed(0.0),
        max: closed(1000.0),
        unit: "cells",
        group: Group::Cells,
        advanced: true,
        summary: "Islands beside their coast beyond",
        help: "An island of one or two regions takes the cell nearest its place under the fit \
             that the location metric makes, unless that lies more than this far from where \
             the cells of the 3 regions of larger landmasses nearest it put it (its place as \
             seen from theirs); then it goes there, beside its coast. Where the layout bends \
             the map far from the fit (a sparse coast beside a crowded capital), an island \
             sent to its fitted place sat alone out at sea (Cozumel 16 cells from its coast \
             among Mexico's 2,458 municipalities); on world_countries no island is more than \
             4.3 cells from where its coast puts it, and there the fit places it better. 1000 \
             turns this off.",
        access: accessors!(island_limit, Real),
    },
    Parameter {
        name: "group_gap",
        kind: Kind::Integer { bits: 32 },
        optional: false,
        min: closed(0.0),
        max: closed(1.0),
        unit: "cells",
        group: Group::Groups,
        advanced: false,
        summary: "Gap between groups",
        help: "With a group field, the regions of each group form one block of cells on each \
             landmass; 1 leaves an empty cell between the blocks of different groups (no cell of \
             one touches a cell of another, not even at a corner), 0 packs them together.",
        access: accessors!(group_gap, Integer),
    },
    Parameter {
        name: "shifts",
        kind: Kind::PairList { min: 1, max: 16 },
        optional: false,
        min: closed(0.0),
        max: open(1.0),
        unit: "cells",
        group: Group::Candidates,
        advanced: true,
        summary: "Lattice origin shifts",
        help: "Shifts x:y of the lattice's origin (x right, y down), as fractions of a cell: one \
             candidate layout each (Strategy 2). For hexagons, along the lattice's own axes: x \
             along a row (pointy) or column (flat), y along the next row's (column's) offset.",
        access: accessors!(shifts, Pairs),
    },
    Parameter {
        name: "noise_levels",
        kind: Kind::RealList { min: 0, max: 8 },
        optional: false,
        min: closed(0.0),
        max: closed(1.0),
        unit: "",
        group: Group::Candidates,
        advanced: true,
        summary: "Centroid noise levels",
        help: "Noise levels MD of the extra Snake runs (Strategy 1): each moves every centroid by \
             Gaussian noise of MD times its mean neighbour distance; the noise-free run is \
             always made.",
        access: accessors!(noise_levels, Reals),
    },
    Parameter {
        name: "max_layouts",
        kind: Kind::Integer { bits: 32 },
        optional: true,
        min: closed(1.0),
        max: closed(1000.0),
        unit: "layouts",
        group: Group::Candidates,
        advanced: true,
        summary: "Most candidate layouts",
        help: "How many of the (Snake run, shift) pairs are laid out and ranked, taken with the \
             Snake runs in turn and the shifts spread over the cell. none: every pair up to \
             1,000 regions, then about 27,000 / regions (at least 1), since the lattice's \
             position matters less the more regions share it.",
        access: accessors!(max_layouts, OptionalInteger),
    },
    Parameter {
        name: "max_refined",
        kind: Kind::Integer { bits: 32 },
        optional: true,
        min: closed(1.0),
        max: closed(1000.0),
        unit: "layouts",
        group: Group::Candidates,
        advanced: true,
        summary: "Most refined layouts",
        help: "How many of the candidate layouts are refined: the best ones by the same \
             ranking before refinement, which picks the best refined one too (the refinement \
             moves every candidate about alike). none: every candidate up to 222 regions, then \
             about 6,000 / regions, and one from 3,000 regions on (refined in stripes on \
             every core), since the refinement is most of a layout's time.",
        access: accessors!(max_refined, OptionalInteger),
    },
    Parameter {
        name: "seed",
        kind: Kind::Integer { bits: 64 },
        optional: false,
        min: closed(0.0),
        max: None,
        unit: "",
        group: Group::Candidates,
        advanced: false,
        summary: "Random seed",
        help: "Seed of every random choice (noise, refinement): the same seed gives the same map.",
        access: accessors!(seed, Integer),
    },
    Parameter {
        name: "refine",
        kind: Kind::Bool,
        optional: false,
        min: None,
        max: None,
        unit: "",
        group: Group::Refinement,
        advanced: false,
        summary: "Adjacency-aware refinement",
        help: "Improve the assignment by swapping and moving cells so that neighbours stay \
             neighbours and directions hold (method.md §6b); false gives the paper's method.",
        access: accessors!(refine, Bool),
    },
    Parameter {
        name: "refine_moves_per_region",
        kind: Kind::Integer { bits: 32 },
        optional: false,
        min: closed(0.0),
        max: closed(1e6),
        unit: "moves",
        group: Group::Refinement,
        advanced: true,
        summary: "Refinement moves per region",
        help: "Simulated-annealing moves of the refinement, per region: the budget grows with \
             the layer.",
        access: accessors!(refine_moves_per_region, Integer),
    },
    Parameter {
        name: "refine_temperature",
        kind: Kind::Real,
        optional: false,
        min: closed(0.0),
        max: closed(100.0),
        unit: "",
        group: Group::Refinement,
        advanced: true,
        summary: "Refinement temperature",
        help: "Starting temperature of the annealing, falling linearly to 0; 0 accepts only \
             improvements.",
        access: accessors!(refine_temperature, Real),
    },
    Parameter {
        name: "refine_w_adjacent",
        kind: Kind::Real,
        optional: false,
        min: closed(0.0),
        max: closed(100.0),
        unit: "",
        group: Group::Refinement,
        advanced: true,
        summary: "Refinement weight: lost neighbour",
        help: "Cost of an adjacent pair whose cells are not 8-neighbours.",
        access: accessors!(refine_w_adjacent, Real),
    },
    Parameter {
        name: "refine_w_angle",
        kind: Kind::Real,
        optional: false,
        min: closed(0.0),
        max: closed(100.0),
        unit: "",
        group: Group::Refinement,
        advanced: true,
        summary: "Refinement weight: direction",
        help: "Cost of an adjacent pair's direction error, per 90°.",
        access: accessors!(refine_w_angle, Real),
    },
    Parameter {
        name: "refine_w_misdirected",
        kind: Kind::Real,
        optional: false,
        min: closed(0.0),
        max: closed(100.0),
        unit: "",
        group: Group::Refinement,
        advanced: true,
        summary: "Refinement weight: misdirected pair",
        help: "Cost of an adjacent pair whose direction is off by more than 45°.",
        access: accessors!(refine_w_misdirected, Real),
    },
    Parameter {
        name: "refine_w_location",
        kind: Kind::Real,
        optional: false,
        min: closed(0.0),
        max: closed(100.0),
        unit: "",
        group: Group::Refinement,
        advanced: true,
        summary: "Refinement weight: distance",
        help: "Cost of a region's distance d from its place, in cells: d² up to \
             refine_location_knee, then growing linearly (see there).",
        access: accessors!(refine_w_location, Real),
    },
    Parameter {
        name: "refine_location_knee",
        kind: Kind::Real,
        optional: false,
        min: closed(0.1),
        max: closed(1000.0),
        unit: "cells",
        group: Group::Refinement,
        advanced: true,
        summary: "Refinement: distance cost linear beyond",
        help: "Beyond this distance k from its place a region's distance cost grows linearly, \
             k·(2d − k), as method.md §8 measures location, instead of with the square d²; \
             1000 gives method.md §6b's squared cost everywhere.",
        access: accessors!(refine_location_knee, Real),
    },
    Parameter {
        name: "refine_location_far",
        kind: Kind::Real,
        optional: false,
        min: closed(0.0),
        max: closed(1000.0),
        unit: "cells",
        group: Group::Refinement,
        advanced: true,
        summary: "Refinement: far from home beyond",
        help: "Beyond F, the farther of this distance and where it started, a region keeps at \
             least one of its neighbours beside it, and its distance d from its place costs \
             refine_w_far·(d − F)² more. The linear cost beyond refine_location_knee lets a \
             region with few neighbours be sent far to make room for others (us_states: \
             Washington DC beside Arkansas; world_countries: Kuwait beside Russia): a layout \
             that leaves one alone there is refined again refusing such moves (with thousands \
             of regions, from the start; not with pins). 1000 turns this off.",
        access: accessors!(refine_location_far, Real),
    },
    Parameter {
        name: "refine_w_far",
        kind: Kind::Real,
        optional: false,
        min: closed(0.0),
        max: closed(100.0),
        unit: "",
        group: Group::Refinement,
        advanced: true,
        summary: "Refinement weight: far from home",
        help: "Weight of the squared distance beyond refine_location_far (see there); 0, the \
             default, leaves it out: 1 cut the farthest region's distance by 0.38 cells on \
             average over the shared and generated layers, but cost orientation (BENCHMARKS.md).",
        access: accessors!(refine_w_far, Real),
    },
    Parameter {
        name: "refine_w_landmass",
        kind: Kind::Real,
        optional: false,
        min: closed(0.0),
        max: closed(100.0),
        unit: "",
        group: Group::Refinement,
        advanced: true,
        summary: "Refinement weight: wrong landmass",
        help: "Cost of a region whose cell lies nearer another landmass than its own.",
        access: accessors!(refine_w_landmass, Real),
    },
    Parameter {
        name: "refine_w_notch",
        kind: Kind::Real,
        optional: false,
        min: closed(0.0),
        max: closed(100.0),
        unit: "",
        group: Group::Refinement,
        advanced: true,
        summary: "Refinement weight: notch",
        help: "Cost of an empty position with at most one free side (a hole or a deep bay in \
             the layout).",
        access: accessors!(refine_w_notch, Real),
    },
    Parameter {
        name: "refine_cell_ratio",
        kind: Kind::Real,
        optional: false,
        min: closed(1.0),
        max: closed(10.0),
        unit: "",
        group: Group::Refinement,
        advanced: true,
        summary: "Free cells offered to the refinement",
        help: "The refinement may move regions into the best cells by coverage score, this many \
             times the number of regions.",
        access: accessors!(refine_cell_ratio, Real),
    },
    Parameter {
        name: "refine_swap_only_below",
        kind: Kind::Integer { bits: 32 },
        optional: false,
        min: closed(0.0),
        max: closed(1e9),
        unit: "regions",
        group: Group::Refinement,
        advanced: true,
        summary: "Swap-only refinement for fewer regions than this",
        help: "With fewer regions than this, the refinement only swaps cells, so the layout's \
             outline keeps its shape (moves to free cells can cost a small map its outline).",
        access: accessors!(refine_swap_only_below, Integer),
    },
    Parameter {
        name: "topsis_weights",
        kind: Kind::RealList { min: 4, max: 4 },
        optional: false,
        min: closed(0.0),
        max: closed(1e6),
        unit: "",
        group: Group::Ranking,
        advanced: true,
        summary: "Ranking weights",
        help: "TOPSIS weights of C_location, C_adjacent, C_orientation and C_shape when ranking \
             the candidates; not all 0.",
        access: (
            |p| Value::Reals(p.topsis_weights.to_vec()),
            |p, v| {
                if let Value::Reals(v) = v {
                    if let Ok(w) = v.try_into() {
                        p.topsis_weights = w
                    }
                }
            },
        ),
    },
    Parameter {
        name: "threads",
        kind: Kind::Integer { bits: 32 },
        optional: false,
        min: closed(0.0),
        max: closed(1024.0),
        unit: "threads",
        group: Group::Run,
        advanced: true,
        summary: "Worker threads",
        help: "Threads the candidates are computed on; 0: as many as the machine has (or \
             RAYON_NUM_THREADS). The result is the same for every value.",
        access: accessors!(threads, Integer),
    },
];

/// The table row of `name`.
pub fn parameter(name: &str) -> Option<&'static Parameter> {
    PARAMETERS.iter().find(|p| p.name == name)
}

/// Region-layouts (regions × candidate layouts) the default budget allows: 27 layouts (three
/// Snake runs, nine shifts) up to 1,000 regions, fewer beyond. The best of 27 layouts of the
/// 3,107 US counties is the first noise-free one, and the 27 differ by at most 0.013 in
/// adjacency and 0.03 cells in location (QUALITY.md, BENCHMARKS.md): with thousands of
/// regions the lattice's position averages out, while the cost grows with every layout.
const REGION_LAYOUTS: usize = 27_000;

/// Region-layouts the default budget refines: every candidate up to 222 regions (all the
/// shared layers but the US counties), fewer beyond, and one from
/// [`super::refine::STRIPE_REGIONS`] regions on, refined in stripes on every core. Measured on
/// 27 candidates of 3,000 Voronoi regions (BENCHMARKS.md): the ranking of the layouts before
/// refinement and after agree (correlation 0.98), and the best before is the best after; the
/// refinement costs about 1.5 times what the Snake run, assignment and scoring of a layout
/// cost together.
const REFINED_REGION_LAYOUTS: usize = 6_000;

impl Params {
    /// The noise level of each Snake run: the noise-free run, then each positive level.
    pub fn snake_noise_levels(&self) -> Vec<f64> {
        let noisy = self.noise_levels.iter().copied().filter(|&md| md > 0.0);
        std::iter::once(0.0).chain(noisy).collect()
    }

    /// How many candidate layouts a run on `regions` regions makes: `max_layouts`, or by the
    /// number of regions; never more than the (Snake run, shift) pairs there are.
    pub fn layout_count(&self, regions: usize) -> usize {
        let pairs = self.snake_noise_levels().len() * self.shifts.len();
        let budget = self
            .max_layouts
            .unwrap_or_else(|| REGION_LAYOUTS.div_ceil(regions.max(1)));
        budget.clamp(1, pairs.max(1))
    }

    /// How many of `layouts` candidate layouts of `regions` regions are refined: `max_refined`,
    /// or by the number of regions; at least one, at most all of them.
    pub fn refined_count(&self, regions: usize, layouts: usize) -> usize {
        let budget = self.max_refined.unwrap_or_else(|| {
            if regions >= super::refine::STRIPE_REGIONS {
                1
            } else {
                REFINED_REGION_LAYOUTS.div_ceil(regions.max(1))
            }
        });
        budget.clamp(1, layouts.max(1))
    }

    /// Notes on the settings this run leaves unused (`grouped`: some region has a group), so
    /// that a setting asked for and silently ignored does not pass for one applied.
    pub fn unused(&self, grouped: bool) -> Vec<String> {
        let mut notes = Vec::new();
        if self.cell == CellShape::Square && self.hex_orientation == HexOrientation::Flat {
            notes.push(
                "hex_orientation is flat but the cells are squares (cell square): it applies to \
                 hexagons only"
                    .to_string(),
            );
        }
        if self.group_gap > 0 && !grouped {
            notes.push(format!(
                "group_gap is {} but no region has a group: it applies to grouped layouts only",
                self.group_gap
            ));
        }
        notes
    }

    /// Checks every value against its range in [`PARAMETERS`]; the message names the parameter.
    pub fn validate(&self) -> Result<(), String> {
        for parameter in PARAMETERS {
            parameter.check(&parameter.value(self))?;
        }
        if self.topsis_weights.iter().all(|&w| w == 0.0) {
            return Err("parameter topsis_weights must not all be 0".into());
        }
        Ok(())
    }

    /// The names `set` accepts, in the table's order.
    pub fn names() -> impl Iterator<Item = &'static str> {
        PARAMETERS.iter().map(|p| p.name)
    }

    /// Sets one parameter by name from text, as the command line and the C API receive it:
    /// numbers, `true`/`false`, choice names, comma-separated lists (`0.02,0.04`), shifts as
    /// `x:y` pairs (`0:0,0.5:0.5`), and `none` to clear an optional value. The new value is
    /// range-checked; on error nothing changes and the message names the parameter.
    pub fn set(&mut self, name: &str, text: &str) -> Result<(), String> {
        let parameter = parameter(name).ok_or_else(|| format!("unknown parameter {name:?}"))?;
        let value = parameter.parse(text)?;
        parameter.check(&value)?;
        let mut changed = self.clone();
        (parameter.access.1)(&mut changed, value);
        changed.validate()?;
        *self = changed;
        Ok(())
    }
}

/// The parameter table as Markdown (docs/c-api.md holds it; a test keeps the copy current):
/// one table per group, in the table's order.
pub fn markdown() -> String {
    let mut out = String::new();
    let groups = [
        Group::Snake,
        Group::Outline,
        Group::Cells,
        Group::Groups,
        Group::Candidates,
        Group::Refinement,
        Group::Ranking,
        Group::Run,
    ];
    for group in groups {
        let _ = writeln!(out, "**{}**\n", group.title());
        out.push_str("| option | kind | default | range | unit | what it does |\n");
        out.push_str("|---|---|---|---|---|---|\n");
        for p in PARAMETERS.iter().filter(|p| p.group == group) {
            let _ = writeln!(
                out,
                "| `{}` | {} | `{}` | {} | {} | {}. {} |",
                p.name,
                p.kind.as_str(),
                p.default_text(),
                p.range_text(),
                p.unit,
                p.summary,
                p.help
            );
        }
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_round_trip_through_their_text() {
        let defaults = Params::default();
        defaults.validate().unwrap();
        let mut p = Params::default();
        for parameter in PARAMETERS {
            p.set(parameter.name, &parameter.default_text()).unwrap();
        }
        assert_eq!(p, defaults);
    }

    #[test]
    fn set_parses_every_kind_of_value() {
        let mut p = Params::default();
        p.set("alpha", "2.5").unwrap();
        p.set("max_steps", "12").unwrap();
        p.set("refine", "no").unwrap();
        p.set("load_model", "Element").unwrap();
        p.set("noise_levels", "0.01, 0.03").unwrap();
        p.set("shifts", "0:0,0.25:0.75").unwrap();
        p.set("simplify_tolerance", "0.2").unwrap();
        p.set("seed", "18446744073709551615").unwrap();
        assert_eq!(p.alpha, 2.5);
        assert_eq!(p.max_steps, 12);
        assert!(!p.refine);
        assert_eq!(p.load_model, LoadModel::Element);
        assert_eq!(p.noise_levels, vec![0.01, 0.03]);
        assert_eq!(p.shifts, vec![[0.0, 0.0], [0.25, 0.75]]);
        assert_eq!(p.simplify_tolerance, Some(0.2));
        assert_eq!(p.seed, u64::MAX);
        p.set("simplify_tolerance", "none").unwrap();
        assert_eq!(p.simplify_tolerance, None);
        p.set("noise_levels", "").unwrap();
        assert!(p.noise_levels.is_empty());
    }

    #[test]
    fn set_refuses_unknown_names_and_bad_values_and_keeps_the_old_value() {
        let mut p = Params::default();
        let cases = [
            ("gamma", "1", "unknown parameter \"gamma\""),
            ("alpha", "-1", "alpha must be in [0.001, 1000]"),
            (
                "alpha",
                "1e308",
                "alpha must be in [0.001, 1000], got 1e308",
            ),
            ("beta", "1e308", "beta must be in"),
            ("spring", "1e-300", "spring must be in [0.0001, 1]"),
            ("alpha", "nan", "alpha: expected a finite number"),
            ("force_cap", "0", "force_cap must be in (0, 1]"),
            ("max_steps", "1.5", "max_steps: expected a whole number"),
            ("max_steps", "4294967296", "below 2^32"),
            ("load_model", "springs", "expected nodal or element"),
            ("shifts", "0.5", "expected x:y pairs"),
            ("shifts", "0:1", "each value must be in [0, 1)"),
            ("shifts", "", "expected x:y pairs"),
            ("topsis_weights", "1,1", "takes 4 numbers"),
            ("topsis_weights", "0,0,0,0", "must not all be 0"),
            ("alpha", "none", "expected a number"),
            ("refine", "maybe", "expected true or false"),
        ];
        for (name, value, message) in cases {
            let err = p.set(name, value).unwrap_err();
            assert!(err.contains(message), "{name} {value}: {err}");
            assert!(err.contains(name), "{err} names {name}");
        }
        assert_eq!(p, Params::default());
    }

    #[test]
    fn the_table_lists_every_field_once_with_help_and_a_range() {
        let names: Vec<&str> = Params::names().collect();
        let mut unique = names.clone();
        unique.sort_unstable();
        unique.dedup();
        assert_eq!(unique.len(), names.len(), "no name twice");
        // Every field of Params appears in its serialised form, and only those.
        let serialised = serde_json::to_value(Params::default()).unwrap();
        let fields = serialised.as_object().unwrap();
        assert_eq!(fields.len(), names.len());
        for p in PARAMETERS {
            assert!(fields.contains_key(p.name), "{} is a field", p.name);
            assert!(!p.summary.is_empty() && !p.help.is_empty());
            assert!(!p.range_text().is_empty());
            assert!(
                !p.summary.contains("up to"),
                "{}: the range says which end",
                p.name
            );
        }
    }

    #[test]
    fn ranges_show_their_open_and_closed_ends() {
        let range = |name| parameter(name).unwrap().range_text();
        assert_eq!(range("force_cap"), "(0, 1]");
        assert_eq!(range("alpha"), "[0.001, 1000]");
        assert_eq!(range("seed"), "[0, 2^64 - 1]");
        assert_eq!(range("shifts"), "1 to 16 x:y pairs, each in [0, 1)");
        assert_eq!(range("load_model"), "nodal or element");
    }

    #[test]
    fn settings_a_run_leaves_unused_are_named() {
        let mut params = Params::default();
        assert!(params.unused(false).is_empty());
        params.set("hex_orientation", "flat").unwrap();
        params.set("group_gap", "1").unwrap();
        let notes = params.unused(false);
        assert_eq!(notes.len(), 2, "{notes:?}");
        assert!(notes[0].starts_with("hex_orientation is flat but the cells are squares"));
        assert!(notes[1].starts_with("group_gap is 1 but no region has a group"));
        // Both apply once the cells are hexagons and the regions have groups.
        params.set("cell", "hex").unwrap();
        assert!(params.unused(true).is_empty());
    }
}
