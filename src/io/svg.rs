//! A picture of the source map and the grid map side by side (`-svg FILE`), so a user can look
//! instead of read. Each region has the same colour in both panels, picked from where its
//! centroid lies on the source map, so a cell far from home stands out; each cell carries the
//! region's short label, all in one font size, abbreviated or cut where it would not fit. Written
//! by hand: the format is simple and the output deterministic; any text is made valid XML 1.0.

use crate::core::geometry::bounds;
use crate::core::{GridMap, Region};
use geo::{BoundingRect, Coord, LineString, Rect, Simplify};
use std::fmt::Write;

/// Width of each panel, pixels.
const PANEL: f64 = 480.0;
const MARGIN: f64 = 12.0;
/// Height of the panel titles.
const TITLE: f64 = 22.0;
/// Outline detail finer than this (pixels) is not drawn, which keeps big layers small.
const DETAIL: f64 = 0.4;
/// Width of a character as a share of the font size (sans-serif, on average).
const EM_PER_CHAR: f64 = 0.6;
/// Share of a cell's side that a label may take.
const LABEL_SPAN: f64 = 0.9;
/// Largest label font size, as a share of a cell's side.
const LABEL_MAX: f64 = 0.4;
/// The label font is never so small that fewer characters than this fit in a cell; longer
/// labels are abbreviated instead.
const LABEL_CHARS: usize = 5;

/// The SVG document. `labels` and `regions` are in input order, as `map.cells` is.
pub(crate) fn render(regions: &[Region], labels: &[String], map: &GridMap) -> String {
    let source_box = bounds(regions.iter().filter_map(|r| r.geometry.bounding_rect()));
    let grid_box = bounds(map.cells.iter().filter_map(|c| c.cell.bounding_rect()));
    let (Some(source_box), Some(grid_box)) = (source_box, grid_box) else {
        return String::new();
    };
    let aspect = |r: &Rect<f64>| r.height() / r.width().max(f64::MIN_POSITIVE);
    let height =
        (PANEL * aspect(&source_box).max(aspect(&grid_box))).clamp(PANEL / 4.0, PANEL * 1.5);
    let source_view = View::fit(source_box, MARGIN, height);
    let grid_view = View::fit(grid_box, 2.0 * MARGIN + PANEL, height);
    let (width, total_height) = (3.0 * MARGIN + 2.0 * PANEL, height + TITLE + 2.0 * MARGIN);

    let mut svg = String::new();
    // Writing to a String cannot fail.
    let _ = writeln!(
        svg,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{width:.0}\" height=\"{total_height:.0}\" \
         viewBox=\"0 0 {width:.0} {total_height:.0}\" font-family=\"sans-serif\">\n\
         <style>path{{stroke:#fff;stroke-width:0.5;fill-rule:evenodd}}polygon{{stroke:#fff;stroke-width:1}}\
         text{{text-anchor:middle;dominant-baseline:central;fill:#222}}</style>\n\
         <rect x=\"0\" y=\"0\" width=\"{width:.0}\" height=\"{total_height:.0}\" fill=\"#fff\" stroke=\"none\"/>"
    );
    let m = &map.metrics;
    let titles = [
        (MARGIN, format!("source: {} regions", regions.len())),
        (
            2.0 * MARGIN + PANEL,
            format!(
                "grid map: C_adjacent {:.3}, C_orientation {:.1}°, C_shape {:.3}",
                m.adjacent, m.orientation, m.shape
            ),
        ),
    ];
    for (x, title) in titles {
        let _ = writeln!(
            svg,
            "<text x=\"{:.1}\" y=\"{:.1}\" font-size=\"14\">{}</text>",
            x + PANEL / 2.0,
            MARGIN + TITLE / 2.0,
            escape(&xml_safe(&title))
        );
    }

    let colours: Vec<String> = map
        .cells
        .iter()
        .map(|c| colour(c.centroid, &source_box))
        .collect();
    for (region, colour) in regions.iter().zip(&colours) {
        let mut path = String::new();
        for polygon in &region.geometry {
            for ring in std::iter::once(polygon.exterior()).chain(polygon.interiors()) {
                push_ring(&mut path, &source_view, ring);
            }
        }
        if !path.is_empty() {
            let _ = writeln!(svg, "<path fill=\"{colour}\" d=\"{}\"/>", path.trim_end());
        }
    }
    // Every cell has the same side, so one font size serves all: the size at which the longest
    // label fits, but no smaller than the size for LABEL_CHARS characters.
    let side = map.cell_size * grid_view.scale;
    let longest = labels
        .iter()
        .map(|l| xml_safe(l).chars().count())
        .max()
        .unwrap_or(0)
        .clamp(2, LABEL_CHARS);
    let font = (LABEL_MAX * side).min(LABEL_SPAN * side / (EM_PER_CHAR * longest as f64));
    // At that size `longest` characters fit: every label does, or is made to.
    let room = longest;
    for ((cell, label), colour) in map.cells.iter().zip(labels).zip(&colours) {
        let Some(rect) = cell.cell.bounding_rect() else {
            continue;
        };
        // The cell's own corners (a square or a hexagon), the closing one left out.
        let exterior = &cell.cell.exterior().0;
        let points: Vec<String> = (exterior[..exterior.len().saturating_sub(1)].iter())
            .map(|&c| {
                let p = grid_view.px(c);
                format!("{:.1},{:.1}", p.x, p.y)
            })
            .collect();
        let centre = grid_view.px(rect.center());
        let _ = writeln!(
            svg,
            "<polygon points=\"{}\" fill=\"{colour}\"/>\
             <text x=\"{:.1}\" y=\"{:.1}\" font-size=\"{font:.1}\">{}</text>",
            points.join(" "),
            centre.x,
            centre.y,
            escape(&fit(&xml_safe(label), room))
        );
    }
    svg.push_str("</svg>\n");
    svg
}

/// Map units to pixels for one panel: y flipped, the box fitted and centred.
struct View {
    scale: f64,
    origin: Coord<f64>,
    offset: Coord<f64>,
}

impl View {
    fn fit(bounds: Rect<f64>, left: f64, height: f64) -> View {
        let scale = (PANEL / bounds.width().max(f64::MIN_POSITIVE))
            .min(height / bounds.height().max(f64::MIN_POSITIVE));
        View {
            scale,
            origin: Coord {
                x: bounds.min().x,
                y: bounds.max().y,
            },
            offset: Coord {
                x: left + (PANEL - bounds.width() * scale) / 2.0,
                y: MARGIN + TITLE + (height - bounds.height() * scale) / 2.0,
            },
        }
    }

    fn px(&self, c: Coord<f64>) -> Coord<f64> {
        Coord {
            x: self.offset.x + (c.x - self.origin.x) * self.scale,
            y: self.offset.y + (self.origin.y - c.y) * self.scale,
        }
    }
}

/// Appends one ring as `M x y L … Z`, simplified to [`DETAIL`] and rounded to 0.1 px; rings that
/// shrink below a triangle are left out.
fn push_ring(path: &mut String, view: &View, ring: &LineString<f64>) {
    let pixels: LineString<f64> = ring.coords().map(|&c| view.px(c)).collect();
    let mut points: Vec<String> = Vec::new();
    for c in pixels.simplify(DETAIL).coords() {
        let point = format!("{:.1} {:.1}", c.x, c.y);
        if points.last() != Some(&point) {
            points.push(point);
        }
    }
    if points.len() < 4 {
        return;
    }
    points.pop(); // the closing point; Z closes the ring
    let _ = write!(path, "M{}Z ", points.join("L"));
}

/// A colour from a position on the source map: hue from west to east, lightness from north to
/// south.
fn colour(at: Coord<f64>, bounds: &Rect<f64>) -> String {
    let unit =
        |v: f64, min: f64, extent: f64| ((v - min) / extent.max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
    let east = unit(at.x, bounds.min().x, bounds.width());
    let south = 1.0 - unit(at.y, bounds.min().y, bounds.height());
    format!("hsl({:.0},60%,{:.0}%)", 300.0 * east, 78.0 - 26.0 * south)
}

/// `label` in at most `room` characters: as it is if it fits, else the initials of its
/// capitalised words ("United States of America" → "USA"), else cut with an ellipsis.
fn fit(label: &str, room: usize) -> String {
    if label.chars().count() <= room {
        return label.to_owned();
    }
    let initials: String = label
        .split_whitespace()
        .filter_map(|word| word.chars().next())
        .filter(|c| c.is_uppercase())
        .collect();
    if (2..=room).contains(&initials.chars().count()) {
        return initials;
    }
    let kept: String = label.chars().take(room.saturating_sub(1)).collect();
    format!("{}…", kept.trim_end())
}

/// `text` without what XML 1.0 cannot hold even escaped: control characters (a tab or line
/// break, allowed but out of place in a one-line label, becomes a space) and U+FFFE, U+FFFF.
fn xml_safe(text: &str) -> String {
    text.chars()
        .filter_map(|c| match c {
            '\t' | '\n' | '\r' => Some(' '),
            c if c.is_control() || c == '\u{FFFE}' || c == '\u{FFFF}' => None,
            c => Some(c),
        })
        .collect()
}

/// `text` with XML's markup characters escaped.
fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for ch in text.chars() {
        match ch {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            _ => out.push(ch),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_that_do_not_fit_are_abbreviated_or_cut() {
        assert_eq!(fit("CA", 4), "CA");
        assert_eq!(fit("United States of America", 4), "USA");
        assert_eq!(fit("Central African Rep.", 4), "CAR");
        assert_eq!(fit("Kazakhstan", 5), "Kaza…");
        assert_eq!(fit("New caledonia", 3), "Ne…");
    }

    #[test]
    fn text_is_made_valid_xml() {
        assert_eq!(xml_safe("a\u{7}b\tc\u{FFFE}\u{9F}"), "ab c");
        assert_eq!(escape("<&\"'>"), "&lt;&amp;&quot;&apos;&gt;");
    }
}
