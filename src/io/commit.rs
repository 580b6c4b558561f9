//! Putting every output of a run in place together, or none of them.
//!
//! Each output is complete in its staging folder before the commit starts. The commit first
//! checks everything a rename could trip on (a file of the source, a name already taken without
//! `-overwrite`, a sticky folder where another user owns what would be replaced), then, for every
//! output in turn: keeps what it replaces (a hard link into the staging folder, so the rename of
//! the new file over the old one stays atomic; a rename aside for folders or where links fail),
//! renames the new files into place and removes the old files the new output has no counterpart
//! for (a Shapefile's stale `.qix`). Should any step fail, every step done is undone in reverse
//! order, so that every destination holds exactly what it held before; the message says what
//! failed and, should undoing fail too, what was replaced and where the old files are kept.

use super::paths::SourceFiles;
use super::staging::{folder_of, Staging};
use crate::core::Error;
use std::collections::BTreeSet;
use std::fs::{self, File};
use std::os::unix::fs::{MetadataExt, PermissionsExt};
use std::path::{Path, PathBuf};

/// The sub-folder of a staging folder that keeps what the output replaced until the commit ends.
const REPLACED: &str = ".replaced";

/// One output, written whole in its staging folder.
pub(crate) struct Staged {
    /// What the output is called in messages ("destination", "JSON report", "picture").
    pub what: &'static str,
    pub destination: PathBuf,
    pub staging: Staging,
    /// What the output replaces (the files of the old dataset), found when the run started.
    pub displaced: Vec<PathBuf>,
}

/// One step of a commit, as it is undone.
enum Step {
    /// `original` is kept at `kept` (a hard link or the original itself, renamed).
    Kept { original: PathBuf, kept: PathBuf },
    /// A new file renamed from `staged` to `placed`.
    Placed { staged: PathBuf, placed: PathBuf },
}

/// An output checked for the commit: what moves where, and what it replaces.
struct Move<'a> {
    output: &'a Staged,
    /// (staged, destination) of every file the output is made of.
    files: Vec<(PathBuf, PathBuf)>,
    replaced: Vec<PathBuf>,
}

/// Moves every output into place, or leaves every destination as it was. `overwrite`: files
/// already at the outputs' names may be replaced. Every file is checked once more against the
/// `source` files first: a driver may write sidecars that the checks before the run could not
/// foresee.
pub(crate) fn commit(
    outputs: Vec<Staged>,
    overwrite: bool,
    source: &SourceFiles,
) -> Result<(), Error> {
    let moves = outputs
        .iter()
        .map(|output| plan(output, overwrite, source))
        .collect::<Result<Vec<_>, _>>()?;
    for (staged, _) in moves.iter().flat_map(|m| &m.files) {
        sync(staged)?;
    }
    // Each step with the index of its output.
    let mut done: Vec<(usize, Step)> = Vec::new();
    let result = moves
        .iter()
        .enumerate()
        .try_for_each(|(k, m)| apply(m, &mut |step| done.push((k, step))));
    drop(moves);
    let Err(failure) = result else {
        // Durable as well as atomic: the renames reach the disk before the run says done.
        let folders: BTreeSet<PathBuf> =
            outputs.iter().map(|o| folder_of(&o.destination)).collect();
        for folder in folders {
            let _ = File::open(&folder).and_then(|f| f.sync_all());
        }
        return Ok(());
    };
    let unrestored = undo(done);
    if unrestored.is_empty() {
        return Err(Error::Io(format!(
            "{failure}; nothing was replaced (what had been moved was put back)"
        )));
    }
    let mut replaced = Vec::new();
    let mut kept = Vec::new();
    for (k, output) in outputs.into_iter().enumerate() {
        if unrestored.contains(&k) {
            replaced.push(format!(
                "the {} {:?}",
                output.what,
                output.destination.display()
            ));
            kept.push(format!(
                "{:?}",
                output.staging.keep().join(REPLACED).display()
            ));
        }
    }
    Err(Error::Io(format!(
        "{failure}; {} could not be put back as it was (its old files are kept in {})",
        replaced.join(" and "),
        kept.join(" and ")
    )))
}

/// What `output` moves and replaces, refusing what would make a rename fail or lose a file.
fn plan<'a>(output: &'a Staged, overwrite: bool, source: &SourceFiles) -> Result<Move<'a>, Error> {
    let listing = |dir: &Path| -> Result<Vec<PathBuf>, Error> {
        let cannot = |e| Error::Io(format!("cannot list {:?}: {e}", dir.display()));
        let mut names = fs::read_dir(dir)
            .map_err(cannot)?
            .map(|entry| entry.map(|e| e.file_name()))
            .collect::<Result<Vec<_>, _>>()
            .map_err(cannot)?;
        names.sort();
        Ok(names.into_iter().map(PathBuf::from).collect())
    };
    let folder = folder_of(&output.destination);
    let files: Vec<(PathBuf, PathBuf)> = listing(output.staging.dir())?
        .into_iter()
        .filter(|name| name != Path::new(REPLACED))
        .map(|name| (output.staging.dir().join(&name), folder.join(&name)))
        .collect();
    if files.is_empty() {
        return Err(Error::Io(format!(
            "the {} {:?} was not written (the driver left nothing)",
            output.what,
            output.destination.display()
        )));
    }
    // Every path in the destination's folder, spelled one way, so that they compare.
    let mut replaced: Vec<PathBuf> = output
        .displaced
        .iter()
        .filter_map(|path| path.file_name())
        .map(|name| folder.join(name))
        .collect();
    for (_, destination) in &files {
        source.refuse(output.what, destination)?;
        if fs::symlink_metadata(destination).is_ok() && !replaced.contains(destination) {
            if !overwrite {
                return Err(Error::Io(format!(
                    "{:?} already exists (use -overwrite to replace it)",
                    destination.display()
                )));
            }
            replaced.push(destination.clone());
        }
    }
    replaced.retain(|path| fs::symlink_metadata(path).is_ok());
    // In a sticky folder (/tmp) only the owner of a file may rename or remove it.
    let sticky = fs::metadata(&folder).is_ok_and(|m| m.permissions().mode() & 0o1000 != 0);
    let me = fs::metadata(output.staging.dir()).map(|m| m.uid()).ok();
    if sticky && me != Some(0) {
        for path in &replaced {
            if let (Ok(file), Some(me)) = (fs::symlink_metadata(path), me) {
                if file.uid() != me {
                    return Err(Error::Io(format!(
                        "cannot replace {:?}: another user owns it in a folder where only the \
                         owner may replace a file",
                        path.display()
                    )));
                }
            }
        }
    }
    Ok(Move {
        output,
        files,
        replaced,
    })
}

/// Flushes a staged file (or every file in a staged folder) to the disk.
fn sync(path: &Path) -> Result<(), Error> {
    let cannot = |e| Error::Io(format!("cannot write {:?}: {e}", path.display()));
    if path.is_dir() {
        for entry in fs::read_dir(path).map_err(cannot)? {
            sync(&entry.map_err(cannot)?.path())?;
        }
        Ok(())
    } else {
        File::open(path).and_then(|f| f.sync_all()).map_err(cannot)
    }
}

/// Commits one output, passing each step done to `record`.
fn apply(m: &Move, record: &mut dyn FnMut(Step)) -> Result<(), String> {
    let keep_dir = m.output.staging.dir().join(REPLACED);
    let shown = m.output.destination.display();
    let what = m.output.what;
    if !m.replaced.is_empty() {
        fs::create_dir(&keep_dir)
            .map_err(|e| format!("cannot set the old {what} {shown:?} aside: {e}"))?;
    }
    for (k, original) in m.replaced.iter().enumerate() {
        let kept = keep_dir.join(format!(
            "{k}-{}",
            original.file_name().unwrap_or_default().to_string_lossy()
        ));
        // A link keeps the old file while the new one is renamed over it (atomic); a folder, or
        // a file system without hard links, moves aside instead.
        let is_dir = fs::symlink_metadata(original).is_ok_and(|m| m.is_dir());
        let linked = !is_dir && fs::hard_link(original, &kept).is_ok();
        if !linked {
            fs::rename(original, &kept)
                .map_err(|e| format!("cannot set {:?} aside: {e}", original.display()))?;
        }
        record(Step::Kept {
            original: original.clone(),
            kept,
        });
    }
    for (staged, placed) in &m.files {
        fs::rename(staged, placed).map_err(|e| {
            format!(
                "cannot move the {what} into place at {:?}: {e}",
                placed.display()
            )
        })?;
        record(Step::Placed {
            staged: staged.clone(),
            placed: placed.clone(),
        });
    }
    // Old files the new output has no counterpart for (still there when they were linked).
    for original in &m.replaced {
        let renamed_over = m.files.iter().any(|(_, placed)| placed == original);
        if !renamed_over && fs::symlink_metadata(original).is_ok() {
            fs::remove_file(original)
                .map_err(|e| format!("cannot remove the old {:?}: {e}", original.display()))?;
        }
    }
    Ok(())
}

/// Undoes `done` in reverse order; returns the outputs that could not be restored.
fn undo(done: Vec<(usize, Step)>) -> BTreeSet<usize> {
    let mut unrestored = BTreeSet::new();
    for (output, step) in done.into_iter().rev() {
        let restored = match step {
            Step::Placed { staged, placed } => fs::rename(&placed, &staged).is_ok(),
            // A linked original may still be in place; a renamed or removed one is not.
            Step::Kept { original, kept } => {
                fs::symlink_metadata(&original).is_ok() || fs::rename(&kept, &original).is_ok()
            }
        };
        if !restored {
            unrestored.insert(output);
        }
    }
    unrestored
}

#[cfg(test)]
mod tests {
    use super::*;

    fn staged(dir: &Path, name: &str, what: &'static str, content: &[u8]) -> Staged {
        let destination = dir.join(name);
        let staging = Staging::new(&destination, what).unwrap();
        fs::write(staging.path(), content).unwrap();
        Staged {
            what,
            displaced: vec![destination.clone()],
            destination,
            staging,
        }
    }

    fn nothing_from_the_source() -> SourceFiles {
        SourceFiles::none()
    }

    #[test]
    fn every_output_is_replaced_together() {
        let scratch = tempfile::tempdir().unwrap();
        for name in ["a.gpkg", "a.json"] {
            fs::write(scratch.path().join(name), b"old").unwrap();
        }
        let outputs = vec![
            staged(scratch.path(), "a.gpkg", "destination", b"new grid"),
            staged(scratch.path(), "a.json", "JSON report", b"new report"),
        ];
        commit(outputs, true, &nothing_from_the_source()).unwrap();
        assert_eq!(
            fs::read(scratch.path().join("a.gpkg")).unwrap(),
            b"new grid"
        );
        assert_eq!(
            fs::read(scratch.path().join("a.json")).unwrap(),
            b"new report"
        );
        let left: Vec<_> = fs::read_dir(scratch.path()).unwrap().collect();
        assert_eq!(left.len(), 2, "no staging folder is left");
    }

    #[test]
    fn a_failure_after_the_first_rename_puts_everything_back() {
        let scratch = tempfile::tempdir().unwrap();
        for name in ["a.gpkg", "a.svg"] {
            fs::write(scratch.path().join(name), b"old").unwrap();
        }
        let first = staged(scratch.path(), "a.gpkg", "destination", b"new grid");
        let second = staged(scratch.path(), "a.svg", "picture", b"new picture");
        // The picture's staged file vanishes between the checks and its rename: the rename of
        // the destination, done first, must be undone.
        let outputs = [first, second];
        let moves: Vec<Move> = outputs
            .iter()
            .map(|o| plan(o, true, &nothing_from_the_source()).unwrap())
            .collect();
        fs::remove_file(outputs[1].staging.path()).unwrap();
        let mut done = Vec::new();
        let failure = moves
            .iter()
            .try_for_each(|m| apply(m, &mut |step| done.push((0, step))))
            .unwrap_err();
        assert!(
            failure.contains("cannot move the picture into place"),
            "{failure}"
        );
        assert!(undo(done).is_empty());
        for name in ["a.gpkg", "a.svg"] {
            assert_eq!(
                fs::read(scratch.path().join(name)).unwrap(),
                b"old",
                "{name}"
            );
        }
    }

    #[test]
    fn old_files_without_a_new_counterpart_go_and_stray_names_need_overwrite() {
        let scratch = tempfile::tempdir().unwrap();
        let dir = scratch.path();
        fs::write(dir.join("g.shp"), b"old shp").unwrap();
        fs::write(dir.join("g.qix"), b"old index").unwrap();
        let output = staged(dir, "g.shp", "destination", b"new shp");
        fs::write(output.staging.dir().join("g.dbf"), b"new dbf").unwrap();
        fs::write(dir.join("g.dbf"), b"stray").unwrap();
        let displaced = vec![dir.join("g.shp"), dir.join("g.qix")];
        let output = Staged {
            displaced: displaced.clone(),
            ..output
        };
        let error = commit(vec![output], false, &nothing_from_the_source()).unwrap_err();
        assert!(
            error.to_string().contains("g.dbf\" already exists"),
            "{error}"
        );
        assert_eq!(fs::read(dir.join("g.dbf")).unwrap(), b"stray");
        assert_eq!(fs::read(dir.join("g.shp")).unwrap(), b"old shp");

        let output = staged(dir, "g.shp", "destination", b"new shp");
        fs::write(output.staging.dir().join("g.dbf"), b"new dbf").unwrap();
        let output = Staged {
            displaced,
            ..output
        };
        commit(vec![output], true, &nothing_from_the_source()).unwrap();
        assert_eq!(fs::read(dir.join("g.shp")).unwrap(), b"new shp");
        assert_eq!(fs::read(dir.join("g.dbf")).unwrap(), b"new dbf");
        assert!(!dir.join("g.qix").exists(), "the stale index is gone");
    }
}
