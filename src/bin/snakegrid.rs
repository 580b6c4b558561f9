//! `snakegrid [options] DST SRC [SRC_LAYER]`: a grid map from any polygon layer GDAL reads, in
//! the style of ogr2ogr (single-dash long options such as `-nln`, `-overwrite`, `-where`).

use clap::{Arg, ColorChoice, Command, CommandFactory, FromArgMatches, Parser};
use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
use signal_hook::{flag, low_level};
use snakegrid::io::{self, Job};
use snakegrid::{Error, Params, PARAMETERS};
use std::ffi::{c_int, OsString};
use std::io::{IsTerminal, Write};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

/// Make a grid map (tile map): one equal cell per region (squares, or hexagons with -cell hex),
/// placed so that cells stay near their regions, neighbours stay neighbours, directions hold and
/// the whole keeps the map's outline (the snake model of Wei, Yang, Xu and Ding, 2024, with an
/// adjacency-aware refinement).
///
/// The output layer has every source field, then grid_col and grid_row (the cell, from the top
/// left), grid_q and grid_r (axial coordinates, for hexagons), cell_disp (distance from the
/// region to its cell, in cells), nbr_kept (share of the region's neighbours kept), orient_err
/// (mean direction error to its neighbours, degrees) and grid_group (the cell's block: its
/// group on its landmass with -group, else its landmass).
#[derive(Parser, Debug)]
#[command(name = "snakegrid", color = ColorChoice::Never, max_term_width = 100)]
struct Cli {
    /// Destination dataset, a file or folder (must not exist, unless -overwrite); /vsistdout/ (with -f) sends it to standard output once the run has succeeded
    #[arg(value_name = "DST")]
    dst: String,
    /// Source dataset: file, folder or connection string
    #[arg(value_name = "SRC")]
    src: String,
    /// Source layer [default: the first layer, with a note naming the others]
    #[arg(value_name = "SRC_LAYER")]
    src_layer: Option<String>,
    /// Output format, a GDAL vector driver short name [default: from DST's extension (refused if no driver writes it); GPKG without one]
    #[arg(short = 'f', value_name = "FORMAT", allow_hyphen_values = true)]
    format: Option<String>,
    /// Name of the output layer [default: the source layer's name]
    #[arg(long = "nln", value_name = "NAME", allow_hyphen_values = true)]
    nln: Option<String>,
    /// Replace the layer in DST (or DST itself, for a single-layer format) and the -json and -svg
    /// files if they exist, once the run has succeeded
    #[arg(long = "overwrite")]
    overwrite: bool,
    /// Add the layer to the existing dataset DST (refused if it has a layer of that name)
    #[arg(long = "update")]
    update: bool,
    /// Source CRS, any definition GDAL accepts, in place of the one the source has
    #[arg(long = "s_srs", value_name = "CRS", allow_hyphen_values = true)]
    s_srs: Option<String>,
    /// Only the features matching this OGR SQL attribute filter
    #[arg(long = "where", value_name = "EXPR", allow_hyphen_values = true)]
    where_clause: Option<String>,
    /// Field with each region's unique id (any type) [default: the feature id]
    #[arg(long = "id", value_name = "FIELD", allow_hyphen_values = true)]
    id: Option<String>,
    /// Field whose regions keep together: one block of cells per group on each landmass (a
    /// null or blank value is a group of its own region; see group_gap)
    #[arg(long = "group", value_name = "FIELD", allow_hyphen_values = true)]
    group: Option<String>,

    /// Field with the column of each pinned region's cell (whole numbers; null: free). With
    /// pins, grid_col and grid_row are numbered in the pins' frame
    #[arg(
        long = "pin_col",
        value_name = "FIELD",
        allow_hyphen_values = true,
        requires = "pin_row"
    )]
    pin_col: Option<String>,

    /// Field with the row of each pinned region's cell, from the top (see -pin_col)
    #[arg(
        long = "pin_row",
        value_name = "FIELD",
        allow_hyphen_values = true,
        requires = "pin_col"
    )]
    pin_row: Option<String>,
    /// Working and output CRS, any definition GDAL accepts [default: the source CRS; a geographic
    /// source is projected to Lambert azimuthal equal-area centred on the layer, a world layer
    /// (over 180° of longitude) to Equal Earth, one round a pole to Lambert azimuthal on the pole]
    #[arg(long = "t_srs", value_name = "CRS", allow_hyphen_values = true)]
    t_srs: Option<String>,
    /// Write a machine-readable report (parameters, metrics, Snake run, candidates, regions)
    #[arg(long = "json", value_name = "FILE", allow_hyphen_values = true)]
    json: Option<String>,
    /// Write a picture of the source map and the grid map side by side
    #[arg(long = "svg", value_name = "FILE", allow_hyphen_values = true)]
    svg: Option<String>,
    /// Also write the layout as HexJSON (Open Innovations' format; needs -cell hex)
    #[arg(long = "hexjson", value_name = "FILE", allow_hyphen_values = true)]
    hexjson: Option<String>,
    /// Short name field for the cells of the -svg picture [default: abbr, else name, else the id]
    #[arg(long = "label", value_name = "FIELD", allow_hyphen_values = true)]
    label: Option<String>,
    /// Layer creation option of the output driver (repeatable)
    #[arg(long = "lco", value_name = "NAME=VALUE", allow_hyphen_values = true)]
    lco: Vec<String>,
    /// Dataset creation option of the output driver (repeatable)
    #[arg(long = "dsco", value_name = "NAME=VALUE", allow_hyphen_values = true)]
    dsco: Vec<String>,
    /// Quiet: no progress line and no summary
    #[arg(short = 'q', long = "quiet")]
    quiet: bool,
}

/// The command: the options above plus one `-name VALUE` option per method parameter, from the
/// parameter table, grouped by the step of the method and in the table's order.
fn command() -> Command {
    // Without clap's "string" feature, texts built at run time must be 'static; they are made
    // once, at start-up, and live as long as the program anyway.
    let version: &'static str = format!(
        "{} (GDAL {})",
        env!("CARGO_PKG_VERSION"),
        gdal::version::version_info("RELEASE_NAME")
    )
    .leak();
    let parameters = PARAMETERS.iter().map(|p| {
        let unit = if p.unit.is_empty() {
            String::new()
        } else {
            format!(", {}", p.unit)
        };
        let help = format!(
            "{}; {}{unit} [default: {}]",
            p.summary,
            p.range_text(),
            p.default_text()
        );
        Arg::new(p.name)
            .long(p.name)
            .value_name("VALUE")
            .allow_hyphen_values(true)
            .help(help.leak() as &'static str)
            .help_heading(p.group.title())
    });
    Cli::command().version(version).args(parameters).after_help(
        "Long options may be written with one dash, as in ogr2ogr: -nln, -overwrite, -where, \
             -alpha 2.\nExit status: 0 on success, 1 on error, 2 on a usage error; on error no \
             output is left behind. SIGINT, SIGTERM and SIGHUP stop the run, remove what it was \
             writing and end the process by the same signal.",
    )
}

/// ogr2ogr spells long options with one dash (`-nln`); clap wants two. Every `-word` becomes
/// `--word` (an unknown one too, so clap names it instead of reading `-foo` as `-f oo`); values
/// of options that take one are passed through untouched, even when they start with a dash.
fn ogr_style(args: Vec<OsString>, command: &Command) -> Vec<OsString> {
    let takes_value = |name: &str| {
        command.get_arguments().any(|a| {
            (a.get_long() == Some(name) || a.get_short().is_some_and(|s| name == s.to_string()))
                && a.get_action().takes_values()
        })
    };
    let mut out = Vec::with_capacity(args.len());
    let mut args = args.into_iter();
    out.extend(args.next()); // the program name
    while let Some(arg) = args.next() {
        let Some(text) = arg.to_str() else {
            out.push(arg);
            continue;
        };
        if text == "--" {
            out.push(arg);
            out.extend(args);
            break;
        }
        let (spelled, word) = match text.strip_prefix("--") {
            Some(word) => (arg.clone(), word),
            None => match text.strip_prefix('-') {
                Some(word)
                    if word.chars().count() > 1
                        && !word.starts_with(|c: char| c.is_ascii_digit() || c == '.') =>
                {
                    (OsString::from(format!("-{text}")), word)
                }
                Some(word) => (arg.clone(), word),
                None => {
                    out.push(arg);
                    continue;
                }
            },
        };
        out.push(spelled);
        if !word.contains('=') && takes_value(word) {
            out.extend(args.next());
        }
    }
    out
}

/// clap's error as one line, in the user's spelling: "unexpected argument '-foo' found".
fn one_line(error: &clap::Error, original: &[OsString]) -> String {
    let rendered = error.render().to_string();
    let mut line = rendered
        .lines()
        .map(str::trim)
        .take_while(|l| !l.starts_with("Usage:"))
        .filter(|l| !l.is_empty() && !l.starts_with("tip:"))
        .collect::<Vec<_>>()
        .join(" ");
    line = line.trim_start_matches("error:").trim().to_owned();
    for arg in original.iter().filter_map(|a| a.to_str()) {
        if arg.starts_with('-') && !arg.starts_with("--") {
            line = line.replace(&format!("'-{arg}'"), &format!("'{arg}'"));
        }
    }
    line
}

/// GDAL's progress line, "0...10...20...30...40...50...60...70...80...90...100 - done.", on
/// stderr: 40 ticks, a number every 4. Fractions come from worker threads, possibly out of
/// order: the line only ever moves forward. On a terminal the stage at work ("Snake step 4 of
/// 30", "layout 2 of 9: refining") follows the ticks and is rubbed out before the next ones,
/// so that a pipe or log still gets GDAL's line exactly.
struct TermProgress {
    line: Mutex<Line>,
    terminal: bool,
}

struct Line {
    /// Ticks printed so far; -1 before the first.
    ticks: i32,
    /// The stage shown after the ticks, to rub out.
    stage: String,
}

impl TermProgress {
    fn new() -> Self {
        TermProgress {
            line: Mutex::new(Line {
                ticks: -1,
                stage: String::new(),
            }),
            terminal: std::io::stderr().is_terminal(),
        }
    }

    fn update(&self, fraction: f64, stage: &str) -> bool {
        // The lock is held while printing, or two threads could print their parts swapped.
        let mut line = self
            .line
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner());
        // The line starts with the first work done: a source refused while it is read (ids the
        // output cannot store, say) gets the error line alone.
        if line.ticks < 0 && fraction <= 0.0 {
            return true;
        }
        let text = advance(&mut line.ticks, fraction);
        let restage = self.terminal && line.ticks < 40 && stage != line.stage;
        if text.is_empty() && !restage {
            return true;
        }
        let mut out = String::new();
        if self.terminal && !line.stage.is_empty() {
            // Back over " stage", then clear to the end of the line.
            out += &"\u{8}".repeat(line.stage.chars().count() + 1);
            out += "\x1b[K";
            line.stage.clear();
        }
        out += &text;
        if self.terminal && line.ticks < 40 {
            out += &format!(" {stage}");
            line.stage = stage.to_owned();
        }
        let mut err = std::io::stderr().lock();
        let _ = err.write_all(out.as_bytes());
        let _ = err.flush();
        true
    }

    /// Ends an unfinished line, so that an error message starts on its own.
    fn interrupt(&self) {
        let ticks = self
            .line
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
            .ticks;
        if (0..40).contains(&ticks) {
            eprintln!();
        }
    }
}

/// The text that takes the line from `ticks` printed to `fraction` (empty when it is there).
fn advance(ticks: &mut i32, fraction: f64) -> String {
    let mut text = String::new();
    if !fraction.is_finite() {
        return text;
    }
    let target = (fraction.clamp(0.0, 1.0) * 40.0).floor() as i32;
    while *ticks < target {
        *ticks += 1;
        if *ticks % 4 == 0 {
            text += &(*ticks / 4 * 10).to_string();
        } else {
            text.push('.');
        }
        if *ticks == 40 {
            text += " - done.\n";
        }
    }
    text
}

/// The signals that end a run early. The run stops at its next progress report, which removes
/// its staging folders, and the process then ends by the same signal, so that the shell sees
/// 130, 143 or 129 and a script stops too.
const TERMINATING: [c_int; 3] = [SIGINT, SIGTERM, SIGHUP];

/// Catches [`TERMINATING`]; the number it returns becomes the first signal caught (0: none). A
/// second signal ends the process at once, for a user who will not wait for the cleanup.
fn catch_signals() -> Arc<AtomicUsize> {
    let caught = Arc::new(AtomicUsize::new(0));
    let once = Arc::new(AtomicBool::new(false));
    for signal in TERMINATING {
        // Registered in this order, the first handler sees `once` still false on the first
        // signal. Should registering fail, the signal keeps its default action, which ends the
        // run too, without the cleanup.
        let _ = flag::register_conditional_default(signal, Arc::clone(&once));
        let _ = flag::register(signal, Arc::clone(&once));
        let _ = flag::register_usize(signal, Arc::clone(&caught), signal as usize);
    }
    caught
}

/// Ends the process by `signal`, as if it had not been caught.
fn end_by(signal: c_int, outputs_written: bool) -> ExitCode {
    let name = low_level::signal_name(signal).unwrap_or("a signal");
    let outcome = if outputs_written {
        "it came too late to stop the run: the outputs are complete"
    } else {
        "nothing was written"
    };
    // The terminal may be gone (SIGHUP): a failed write must not stop the rest.
    let _ = writeln!(
        std::io::stderr(),
        "snakegrid: interrupted by {name}; {outcome}"
    );
    let _ = low_level::emulate_default_handler(signal);
    // Not reached for these signals; the shell's own code for them, should it be.
    ExitCode::from(128u8.saturating_add(u8::try_from(signal).unwrap_or(0)))
}

fn usage_error(message: &str) -> ExitCode {
    eprintln!("snakegrid: ERROR: {message} (see --help)");
    ExitCode::from(2)
}

fn main() -> ExitCode {
    let command = command();
    let original: Vec<OsString> = std::env::args_os().collect();
    let matches = match command
        .clone()
        .try_get_matches_from(ogr_style(original.clone(), &command))
    {
        Ok(matches) => matches,
        Err(e)
            if matches!(
                e.kind(),
                clap::error::ErrorKind::DisplayHelp | clap::error::ErrorKind::DisplayVersion
            ) =>
        {
            let _ = e.print();
            return ExitCode::SUCCESS;
        }
        Err(e) => return usage_error(&one_line(&e, &original)),
    };
    let cli = match Cli::from_arg_matches(&matches) {
        Ok(cli) => cli,
        Err(e) => return usage_error(&one_line(&e, &original)),
    };
    let mut params = Params::default();
    for name in Params::names() {
        if let Some(value) = matches.get_one::<String>(name) {
            if let Err(message) = params.set(name, value) {
                return usage_error(&message);
            }
        }
    }
    let job = Job {
        src: cli.src,
        src_layer: cli.src_layer,
        where_clause: cli.where_clause,
        id_field: cli.id,
        group_field: cli.group,
        pin_col_field: cli.pin_col,
        pin_row_field: cli.pin_row,
        dst: cli.dst,
        format: cli.format,
        layer_name: cli.nln,
        overwrite: cli.overwrite,
        update: cli.update,
        source_srs: cli.s_srs,
        target_srs: cli.t_srs,
        json_report: cli.json,
        svg: cli.svg,
        hexjson: cli.hexjson,
        label_field: cli.label,
        dataset_options: cli.dsco,
        layer_options: cli.lco,
    };
    let progress = TermProgress::new();
    let quiet = cli.quiet;
    let caught = catch_signals();
    let interrupted = || caught.load(Ordering::SeqCst) as c_int;
    // A caught signal cancels the run through its progress reports, as a host's callback would.
    let result = io::run(&job, &params, &|fraction, stage| {
        interrupted() == 0 && (quiet || progress.update(fraction, stage))
    });
    let signal = interrupted();
    if signal != 0 {
        progress.interrupt();
        // An error other than the cancellation the signal caused is still worth reading.
        if let Some(e) = result
            .as_ref()
            .err()
            .filter(|e| !matches!(e, Error::Cancelled))
        {
            let _ = writeln!(std::io::stderr(), "snakegrid: ERROR: {e}");
        }
        return end_by(signal, result.is_ok());
    }
    match result {
        Ok(outcome) => {
            if !quiet {
                let summary = io::summary(&job, &outcome);
                // Standard output may carry an output itself (/vsistdout/).
                if io::sends_to_stdout(&job) {
                    eprint!("{summary}");
                } else {
                    print!("{summary}");
                }
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            progress.interrupt();
            eprintln!("snakegrid: ERROR: {e}");
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(list: &[&str]) -> Vec<OsString> {
        list.iter().map(OsString::from).collect()
    }

    #[test]
    fn the_command_is_consistent() {
        command().debug_assert();
    }

    #[test]
    fn single_dash_long_options_become_double_dash_and_values_stay() {
        let command = command();
        let out = ogr_style(
            args(&[
                "snakegrid",
                "-nln",
                "-odd",
                "-overwrite",
                "-f",
                "GPKG",
                "-alpha",
                "-1",
                "-q",
                "out.gpkg",
                "-where=x",
                "--",
                "-src",
            ]),
            &command,
        );
        assert_eq!(
            out,
            args(&[
                "snakegrid",
                "--nln",
                "-odd",
                "--overwrite",
                "-f",
                "GPKG",
                "--alpha",
                "-1",
                "-q",
                "out.gpkg",
                "--where=x",
                "--",
                "-src"
            ])
        );
    }

    #[test]
    fn the_progress_line_is_gdals() {
        let mut ticks = -1;
        let text: String = [0.0, 0.5, 0.3, f64::NAN, 0.99, 1.0, 1.0]
            .into_iter()
            .map(|f| advance(&mut ticks, f))
            .collect();
        assert_eq!(
            text,
            "0...10...20...30...40...50...60...70...80...90...100 - done.\n"
        );
    }
}
