//! HexJSON: the small JSON format of Open Innovations (formerly ODI Leeds) for hexagon maps,
//! <https://open-innovations.org/projects/hexmaps/hexjson>. A document names a `layout` and maps
//! each hexagon's key to its column `q`, its row `r` and any data fields:
//!
//! ```text
//! {"layout": "odd-r", "hexes": {"E14000530": {"q": 1, "r": 4, "n": "Aldershot"}, ...}}
//! ```
//!
//! `-r` layouts are pointy-topped with every other row offset half a hexagon to the right,
//! `-q` layouts flat-topped with every other column offset half a hexagon vertically; `odd` and
//! `even` name which. `r` grows upward (north), unlike snakegrid's rows and SVG's y.
//!
//! **Two readers disagree, and the numbering written here satisfies both.** The format's page
//! and its authors' renderer (odileeds/hexmaps, `resources/oi.hexmap.js`, `updatePos`) take the
//! parity of the *absolute* `q` or `r`, and move the offset columns of `odd-q`/`even-q` half a
//! hexagon *up* (`r += 0.5`, with `r` drawn upward). d3-hexjson (`src/render.js`, `getX`/`getY`,
//! version 1.1.1) first renumbers from the top-left, `qc = q − qmin`, `rc = rmax − r` (so it too
//! draws `r` upward), takes the parity of `qc` or `rc`, and moves the offset columns half a
//! hexagon *down* (`y = rc·w + w` for them, `w/2` for the others, SVG y growing downward). The
//! two agree exactly when `rmax` is even (then `rc ≡ r`) and `qmin` is odd (then `qc ≢ q`, which
//! turns "odd columns up" into "even columns down", the same picture). So [`document`] writes
//!
//! - `q = col − min_col + 1`, so the leftmost column is `q = 1` (odd);
//! - `r = R − (row − min_row)`, with `R` the number of the bottom row counted from the top
//!   rounded up to even, so the top row has the even `r = R` and the bottom row `r = 0` or `1`;
//!
//! and names the layout by the parity of the offset rows (columns) counted from the top row
//! (leftmost column), which is then also their parity in `r` (in `q`, flipped by the `+1`, as
//! the up/down difference needs). Were the two impossible to reconcile, d3-hexjson would win:
//! the grid layer is checked against its centres (`scripts/test-hexjson.sh`).
//!
//! Fields: numbers, and strings of at most 40 characters (labels and codes; longer text would
//! bloat a file meant for a web page), in the order given; other values are left out, and so is
//! a field named `q`, `r` or `n` (the coordinates and the label are never overwritten) or one
//! named like an earlier field. Hexes are written sorted by key (byte order), one a line: the
//! grid map's cells come in the order of the input regions, which the layout does not depend
//! on, so sorting makes the file a function of the layout alone (a reordered input layer gives
//! the same bytes) and keeps diffs small. Keys must be unique; of equal keys the first is kept.

use super::params::HexOrientation;
use super::tiling::Tiling;
use super::GridMap;
use serde_json::Value;

/// One cell in snakegrid's own offset convention: `col` counted from the left (0 = leftmost used
/// column), `row` counted from the TOP (0 = top used row), both ≥ 0. For pointy hexagons the
/// rows whose parity (row % 2) equals [`Layout::shifted`] are offset half a hexagon to the
/// RIGHT; for flat hexagons the columns whose parity equals `shifted` are offset half a hexagon
/// DOWN.
#[derive(Clone, Debug, PartialEq)]
pub struct Hex {
    pub key: String,
    pub col: i32,
    pub row: i32,
    /// Written as `n`, the name the format's renderer labels a hexagon with.
    pub label: Option<String>,
    /// Data fields, written after `q`, `r` and `n` as the module doc says.
    pub fields: Vec<(String, Value)>,
}

/// The lattice the cells lie on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    pub orientation: HexOrientation,
    /// The parity of the offset rows (pointy) or columns (flat): 0 or 1 (taken mod 2).
    pub shifted: i32,
}

/// Why a layout of squares has no HexJSON, with the way out.
pub const NEEDS_HEXAGONS: &str =
    "HexJSON describes hexagons: lay the map out with hexagonal cells (cell hex, -cell hex)";

/// The HexJSON of `map`: each cell keyed by its region's id, with `labels[i]` (input order) as
/// its `n` and `fields[i]` as its data. `None` for a layout of squares ([`NEEDS_HEXAGONS`]).
pub fn of_map(
    map: &GridMap,
    labels: &[String],
    mut fields: Vec<Vec<(String, Value)>>,
) -> Option<String> {
    let (Tiling::Hex(orientation), Some(shifted)) = (map.tiling, map.shifted) else {
        return None;
    };
    fields.resize(map.cells.len(), Vec::new());
    let hexes: Vec<Hex> = (map.cells.iter().zip(fields))
        .enumerate()
        .map(|(i, (cell, fields))| Hex {
            key: cell.id.clone(),
            col: cell.col,
            row: cell.row,
            label: labels.get(i).cloned(),
            fields,
        })
        .collect();
    Some(document(
        &Layout {
            orientation,
            shifted,
        },
        &hexes,
    ))
}

/// The longest string field written, in characters.
const MAX_STRING_CHARS: usize = 40;

/// The HexJSON document of `hexes` on `layout`: `{"layout": "odd-r"|"even-r"|"odd-q"|"even-q",
/// "hexes": {key: {"q": .., "r": .., "n": label, fields..}}}`, numbered as the module doc says
/// (`q ≥ 1` from the left, `r ≥ 0` from the bottom), one hex a line, ending with a newline.
pub fn document(layout: &Layout, hexes: &[Hex]) -> String {
    let min_col = hexes.iter().map(|h| h.col).min().unwrap_or(0);
    let min_row = hexes.iter().map(|h| h.row).min().unwrap_or(0);
    let max_row = hexes.iter().map(|h| h.row).max().unwrap_or(0);
    // The bottom row counted from the top, rounded up to even: the top row's r (see the doc).
    let top_r = i64::from(max_row) - i64::from(min_row);
    let top_r = top_r + top_r % 2;
    // The parity of the offset rows (columns) counted from the top row (leftmost column).
    let first = match layout.orientation {
        HexOrientation::Pointy => min_row,
        HexOrientation::Flat => min_col,
    };
    let odd = (i64::from(layout.shifted) - i64::from(first)).rem_euclid(2) == 1;
    let name = match (layout.orientation, odd) {
        (HexOrientation::Pointy, true) => "odd-r",
        (HexOrientation::Pointy, false) => "even-r",
        (HexOrientation::Flat, true) => "odd-q",
        (HexOrientation::Flat, false) => "even-q",
    };

    let mut order: Vec<&Hex> = hexes.iter().collect();
    order.sort_by(|a, b| a.key.cmp(&b.key)); // stable: of equal keys the first stays first
    order.dedup_by(|later, earlier| later.key == earlier.key);

    let mut out = format!("{{\n  \"layout\": \"{name}\",\n  \"hexes\": {{");
    for (i, hex) in order.iter().enumerate() {
        let q = i64::from(hex.col) - i64::from(min_col) + 1;
        let r = top_r - (i64::from(hex.row) - i64::from(min_row));
        let mut members = vec![
            ("q".to_owned(), Value::from(q)),
            ("r".to_owned(), Value::from(r)),
        ];
        if let Some(label) = &hex.label {
            members.push(("n".to_owned(), Value::from(label.as_str())));
        }
        for (field, value) in &hex.fields {
            let kept = match value {
                Value::Number(_) => true,
                Value::String(s) => s.chars().count() <= MAX_STRING_CHARS,
                _ => false,
            };
            if kept && !members.iter().any(|(m, _)| m == field) {
                members.push((field.clone(), value.clone()));
            }
        }
        let members: Vec<String> = members
            .iter()
            .map(|(m, v)| format!("{}: {v}", Value::from(m.as_str())))
            .collect();
        let separator = if i == 0 { "" } else { "," };
        out.push_str(&format!(
            "{separator}\n    {}: {{{}}}",
            Value::from(hex.key.as_str()),
            members.join(", ")
        ));
    }
    out.push_str(if order.is_empty() {
        "}\n}\n"
    } else {
        "\n  }\n}\n"
    });
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::{json, Map};

    fn hex(key: &str, col: i32, row: i32) -> Hex {
        Hex {
            key: key.to_owned(),
            col,
            row,
            label: None,
            fields: Vec::new(),
        }
    }

    fn parse(text: &str) -> (String, Map<String, Value>) {
        let value: Value = serde_json::from_str(text).expect("valid JSON");
        let layout = value["layout"].as_str().unwrap().to_owned();
        (layout, value["hexes"].as_object().unwrap().clone())
    }

    fn qr(hexes: &Map<String, Value>, key: &str) -> (i64, i64) {
        let h = &hexes[key];
        (h["q"].as_i64().unwrap(), h["r"].as_i64().unwrap())
    }

    const POINTY: HexOrientation = HexOrientation::Pointy;
    const FLAT: HexOrientation = HexOrientation::Flat;

    #[test]
    fn pointy_three_hexes_by_hand() {
        // a at (0, 0), b at (1, 0), c at (0, 1): two rows, the bottom one (row 1) numbered
        // from the top = 1, rounded up to R = 2, so r = 2, 2, 1.
        let hexes = [hex("a", 0, 0), hex("b", 1, 0), hex("c", 0, 1)];
        for (shifted, name) in [(0, "even-r"), (1, "odd-r")] {
            let layout = Layout {
                orientation: POINTY,
                shifted,
            };
            let (got, h) = parse(&document(&layout, &hexes));
            assert_eq!(got, name);
            assert_eq!(
                [qr(&h, "a"), qr(&h, "b"), qr(&h, "c")],
                [(1, 2), (2, 2), (1, 1)]
            );
        }
        // Three rows: the bottom row is 2 from the top, already even, so r = 2 - row.
        let hexes = [hex("a", 0, 0), hex("b", 0, 1), hex("c", 1, 2)];
        let layout = Layout {
            orientation: POINTY,
            shifted: 1,
        };
        let (got, h) = parse(&document(&layout, &hexes));
        assert_eq!(got, "odd-r");
        assert_eq!(
            [qr(&h, "a"), qr(&h, "b"), qr(&h, "c")],
            [(1, 2), (1, 1), (2, 0)]
        );
    }

    #[test]
    fn flat_three_hexes_by_hand() {
        // a at (0, 0), b at (1, 0), c at (2, 1): q = col + 1, rows 0..=1, R = 2.
        let hexes = [hex("a", 0, 0), hex("b", 1, 0), hex("c", 2, 1)];
        for (shifted, name) in [(0, "even-q"), (1, "odd-q")] {
            let layout = Layout {
                orientation: FLAT,
                shifted,
            };
            let (got, h) = parse(&document(&layout, &hexes));
            assert_eq!(got, name);
            assert_eq!(
                [qr(&h, "a"), qr(&h, "b"), qr(&h, "c")],
                [(1, 2), (2, 2), (3, 1)]
            );
        }
    }

    #[test]
    fn cells_not_starting_at_zero_are_renumbered_keeping_the_offsets() {
        // The same cells one column right and one row down, with the parity moved along: the
        // same picture, so the same document.
        let cells = [(0, 0), (1, 0), (0, 1), (1, 2)];
        for orientation in [POINTY, FLAT] {
            for shifted in [0, 1] {
                let at = |dc: i32, dr: i32| -> Vec<Hex> {
                    let mut names = ["a", "b", "c", "d"].iter();
                    cells
                        .iter()
                        .map(|&(c, r)| hex(names.next().unwrap(), c + dc, r + dr))
                        .collect()
                };
                let base = document(
                    &Layout {
                        orientation,
                        shifted,
                    },
                    &at(0, 0),
                );
                let moved = Layout {
                    orientation,
                    shifted: 1 - shifted,
                };
                assert_eq!(document(&moved, &at(1, 1)), base);
                assert_eq!(
                    document(
                        &Layout {
                            orientation,
                            shifted
                        },
                        &at(2, 2)
                    ),
                    base
                );
            }
        }
    }

    /// Centre of a cell in snakegrid's convention, in units of the hexagon's circumradius, y up.
    fn snakegrid_centre(layout: &Layout, col: i32, row: i32) -> (f64, f64) {
        let w = 3f64.sqrt();
        let offset = |i: i32| {
            if i.rem_euclid(2) == layout.shifted {
                0.5
            } else {
                0.0
            }
        };
        match layout.orientation {
            POINTY => (w * (f64::from(col) + offset(row)), -1.5 * f64::from(row)),
            FLAT => (1.5 * f64::from(col), -w * (f64::from(row) + offset(col))),
        }
    }

    /// Where d3-hexjson 1.1.1 puts a hex (its getX/getY, radius 1), y turned up.
    fn d3_centre(name: &str, q: i64, r: i64, qmin: i64, rmax: i64) -> (f64, f64) {
        let w = 3f64.sqrt();
        let (qc, rc) = ((q - qmin) as f64, (rmax - r) as f64);
        let odd = |i: f64| i.rem_euclid(2.0) == 1.0;
        let (x, y_down) = match name {
            "odd-r" => (qc * w + if odd(rc) { w } else { w / 2.0 }, rc * 1.5 + 1.0),
            "even-r" => (qc * w + if !odd(rc) { w } else { w / 2.0 }, rc * 1.5 + 1.0),
            "odd-q" => (qc * 1.5 + 1.0, rc * w + if odd(qc) { w } else { w / 2.0 }),
            "even-q" => (qc * 1.5 + 1.0, rc * w + if !odd(qc) { w } else { w / 2.0 }),
            _ => unreachable!(),
        };
        (x, -y_down)
    }

    /// Where the format's own renderer (oi.hexmap.js, updatePos) puts a hex, radius 1, y up.
    fn format_centre(name: &str, q: i64, r: i64) -> (f64, f64) {
        let w = 3f64.sqrt();
        let (mut q, mut r) = (q as f64, r as f64);
        let odd = |i: f64| i.rem_euclid(2.0) == 1.0;
        match name {
            "odd-r" if odd(r) => q += 0.5,
            "even-r" if !odd(r) => q += 0.5,
            "odd-q" if odd(q) => r += 0.5,
            "even-q" if !odd(q) => r += 0.5,
            _ => {}
        }
        if name.ends_with("-r") {
            (q * w, r * 1.5)
        } else {
            (q * 1.5, r * w)
        }
    }

    fn same_up_to_translation(a: &[(f64, f64)], b: &[(f64, f64)]) -> bool {
        let (dx, dy) = (b[0].0 - a[0].0, b[0].1 - a[0].1);
        a.iter()
            .zip(b)
            .all(|(p, q)| (p.0 + dx - q.0).abs() < 1e-9 && (p.1 + dy - q.1).abs() < 1e-9)
    }

    #[test]
    fn both_renderers_draw_the_cells_where_snakegrid_has_them() {
        // Every orientation and parity, an odd and an even number of rows and columns, and a
        // deliberately wrong layout name that must not match.
        for orientation in [POINTY, FLAT] {
            for shifted in [0, 1] {
                for (cols, rows) in [(3, 3), (4, 4), (3, 4), (4, 3)] {
                    let layout = Layout {
                        orientation,
                        shifted,
                    };
                    let hexes: Vec<Hex> = (0..rows)
                        .flat_map(|row| (0..cols).map(move |col| (col, row)))
                        .filter(|&(col, row)| (col * 7 + row * 3) % 5 != 1 || col == 0 || row == 0)
                        .map(|(col, row)| hex(&format!("c{col}r{row}"), col, row))
                        .collect();
                    let (name, h) = parse(&document(&layout, &hexes));
                    let qmin = h.values().map(|v| v["q"].as_i64().unwrap()).min().unwrap();
                    let rmax = h.values().map(|v| v["r"].as_i64().unwrap()).max().unwrap();
                    assert!(h.values().all(|v| v["r"].as_i64().unwrap() >= 0));
                    let want: Vec<_> = hexes
                        .iter()
                        .map(|c| snakegrid_centre(&layout, c.col, c.row))
                        .collect();
                    let render = |name: &str| -> (Vec<_>, Vec<_>) {
                        hexes
                            .iter()
                            .map(|c| {
                                let (q, r) = qr(&h, &c.key);
                                (d3_centre(name, q, r, qmin, rmax), format_centre(name, q, r))
                            })
                            .unzip()
                    };
                    let (d3, format) = render(&name);
                    assert!(
                        same_up_to_translation(&want, &d3),
                        "d3 {name} {cols}x{rows}"
                    );
                    assert!(
                        same_up_to_translation(&want, &format),
                        "format {name} {cols}x{rows}"
                    );
                    let wrong = if name.starts_with("odd") {
                        name.replacen("odd", "even", 1)
                    } else {
                        name.replacen("even", "odd", 1)
                    };
                    let (d3, format) = render(&wrong);
                    assert!(!same_up_to_translation(&want, &d3));
                    assert!(!same_up_to_translation(&want, &format));
                }
            }
        }
    }

    #[test]
    fn fields_kept_dropped_and_never_over_the_coordinates() {
        let mut h = hex("a", 0, 0);
        h.label = Some("Ab".to_owned());
        h.fields = vec![
            ("pop".to_owned(), json!(12)),
            ("q".to_owned(), json!(99)),
            ("r".to_owned(), json!("x")),
            ("n".to_owned(), json!("other")),
            ("share".to_owned(), json!(0.25)),
            ("code".to_owned(), json!("E".repeat(40))),
            ("essay".to_owned(), json!("é".repeat(41))),
            ("flag".to_owned(), json!(true)),
            ("nothing".to_owned(), Value::Null),
            ("list".to_owned(), json!([1, 2])),
            ("pop".to_owned(), json!(13)),
        ];
        let text = document(
            &Layout {
                orientation: POINTY,
                shifted: 0,
            },
            &[h],
        );
        let (_, hexes) = parse(&text);
        let a = hexes["a"].as_object().unwrap();
        let mut names: Vec<&str> = a.keys().map(String::as_str).collect();
        names.sort_unstable();
        assert_eq!(names, ["code", "n", "pop", "q", "r", "share"]);
        assert_eq!((a["q"].clone(), a["r"].clone()), (json!(1), json!(0)));
        assert_eq!((a["n"].clone(), a["pop"].clone()), (json!("Ab"), json!(12)));
        assert_eq!(a["share"], json!(0.25));
        // Written in order: q, r, n, then the fields as given.
        let line = text.lines().find(|l| l.contains("\"a\"")).unwrap();
        let at = |s: &str| line.find(s).unwrap();
        assert!(at("\"q\"") < at("\"r\"") && at("\"r\"") < at("\"n\""));
        assert!(at("\"n\"") < at("\"pop\"") && at("\"pop\"") < at("\"share\""));
        assert!(at("\"share\"") < at("\"code\""));
    }

    #[test]
    fn keys_escaped_sorted_and_unique() {
        let mut hexes = vec![
            hex("b\"quoted\"\\", 1, 0),
            hex("a\nline\u{1}", 0, 0),
            hex("ä", 0, 1),
            hex("a\nline\u{1}", 1, 1),
        ];
        hexes[1].label = Some("tab\there".to_owned());
        let text = document(
            &Layout {
                orientation: FLAT,
                shifted: 1,
            },
            &hexes,
        );
        assert!(text.ends_with("}\n") && !text.ends_with("\n\n"));
        let (_, h) = parse(&text);
        assert_eq!(h.len(), 3);
        assert_eq!(qr(&h, "a\nline\u{1}"), (1, 2)); // the first of the equal keys
        assert_eq!(h["a\nline\u{1}"]["n"], json!("tab\there"));
        assert_eq!(qr(&h, "b\"quoted\"\\"), (2, 2));
        // One hex a line, in byte order of the keys; the escapes keep each on its line.
        let keys: Vec<&str> = text
            .lines()
            .skip(3)
            .filter(|l| l.starts_with("    "))
            .collect();
        assert_eq!(keys.len(), 3);
        assert!(keys[0].starts_with("    \"a\\n") && keys[1].starts_with("    \"b\\\""));
        assert!(keys[2].starts_with("    \"ä\""));
    }

    #[test]
    fn empty_document() {
        let text = document(
            &Layout {
                orientation: POINTY,
                shifted: 1,
            },
            &[],
        );
        assert_eq!(text, "{\n  \"layout\": \"odd-r\",\n  \"hexes\": {}\n}\n");
        assert!(parse(&text).1.is_empty());
    }
}
