//! Writing a [`Generated`] set into a directory, and `--check`.
//!
//! Ownership: the directory's `manifest.json` lists every file the generator wrote there. A
//! file that exists but is not listed (or a `manifest.json` that is not ours) is foreign:
//! the generator neither overwrites nor deletes it unless `--force`. Files listed in the old
//! manifest that the new run does not produce are ours and are deleted.
//!
//! Every write is atomic (a temporary file in the same directory, then a rename); files whose
//! bytes are unchanged are not rewritten. Before touching any kernel file the new manifest is
//! written listing both the old and the new files, so a run cut short leaves nothing the next
//! run would take for foreign.

use std::collections::BTreeSet;
use std::fs;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use scatter_shaderlib::prefiltered::variant::printable;

use crate::GenError;
use crate::generate::{Generated, MANIFEST};
use crate::manifest::{self, FileEntry, OwnedFiles};

/// What a write did.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct WriteReport {
    /// Files written (new or changed), manifest included.
    pub written: Vec<String>,
    /// Files already up to date.
    pub unchanged: Vec<String>,
    /// Files of an earlier run that this run no longer produces, deleted.
    pub removed: Vec<String>,
}

/// A file `--check` found out of date.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Stale {
    /// Path relative to the directory.
    pub path: String,
    /// `missing`, `differs` or `no longer generated`.
    pub why: &'static str,
}

/// The files an existing manifest in `dir` says the generator owns; `Ok(None)` when there
/// is no manifest.
///
/// # Errors
///
/// [`GenError::Foreign`] when `manifest.json` exists but is not a scatter-gen manifest;
/// [`GenError::Io`] when it cannot be read.
pub fn owned_files(dir: &Path) -> Result<Option<Vec<FileEntry>>, GenError> {
    let path = dir.join(MANIFEST);
    // Bytes, not text: a manifest.json that is not UTF-8 is foreign, not an I/O error.
    let bytes = match fs::read(&path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(GenError::io(path, e)),
    };
    // The manifest's own text (schema, paths) quoted on one printable line.
    let foreign = |why: String| GenError::Foreign {
        path: path.clone(),
        why: printable(&why).into_owned(),
    };
    let owned: OwnedFiles = serde_json::from_slice(&bytes)
        .map_err(|e| foreign(format!("it is not a scatter-gen manifest ({e})")))?;
    if owned.schema != manifest::SCHEMA {
        return Err(foreign(format!(
            "it is not a scatter-gen manifest (schema `{}`)",
            owned.schema
        )));
    }
    for f in &owned.files {
        if !safe_relative(&f.path) {
            return Err(foreign(format!(
                "it lists `{}`, which is not a plain file name inside the directory",
                f.path
            )));
        }
    }
    Ok(Some(owned.files))
}

/// A relative path without `..`, root or drive components.
fn safe_relative(path: &str) -> bool {
    let p = Path::new(path);
    !path.is_empty()
        && p.components()
            .all(|c| matches!(c, std::path::Component::Normal(_)))
}

fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), GenError> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.scatter-gen-{}.tmp", std::process::id()));
    let result = (|| {
        let mut f = fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        fs::rename(&tmp, path)
    })();
    result.map_err(|e| {
        let _ = fs::remove_file(&tmp);
        GenError::io(path, e)
    })
}

fn read_if_exists(path: &Path) -> Result<Option<Vec<u8>>, GenError> {
    match fs::read(path) {
        Ok(b) => Ok(Some(b)),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(e) => Err(GenError::io(path, e)),
    }
}

/// Writes `generated` into `dir` (created if missing).
///
/// # Errors
///
/// [`GenError::Foreign`] (before anything is written) for a file the generator did not
/// create, unless `force`; [`GenError::Io`] when the directory or a file cannot be written.
pub fn write(dir: &Path, generated: &Generated, force: bool) -> Result<WriteReport, GenError> {
    if dir.exists() && !dir.is_dir() {
        return Err(GenError::io(
            dir,
            std::io::Error::other("exists and is not a directory"),
        ));
    }
    let old = if force {
        owned_files(dir).unwrap_or_default()
    } else {
        owned_files(dir)?
    };
    let owned: BTreeSet<String> = old.iter().flatten().map(|f| f.path.clone()).collect();
    let manifest_exists = dir.join(MANIFEST).exists();

    // Refuse before writing anything.
    if !force {
        for f in &generated.files {
            let path = dir.join(&f.path);
            if path.exists() && !owned.contains(&f.path) {
                return Err(GenError::Foreign {
                    path,
                    why: if manifest_exists {
                        format!("it is not listed in {MANIFEST}, so scatter-gen did not write it")
                    } else {
                        format!("there is no {MANIFEST}, so scatter-gen did not write it")
                    },
                });
            }
        }
    }

    fs::create_dir_all(dir).map_err(|e| GenError::io(dir, e))?;
    let mut report = WriteReport::default();

    // Phase 1: a manifest that owns both the old and the new files.
    let new_paths: BTreeSet<&str> = generated.files.iter().map(|f| f.path.as_str()).collect();
    let pending = !owned.iter().all(|p| new_paths.contains(p.as_str()))
        || generated.files.iter().any(|f| !owned.contains(&f.path));
    if pending {
        let mut all: Vec<FileEntry> = old
            .iter()
            .flatten()
            .filter(|f| !new_paths.contains(f.path.as_str()))
            .cloned()
            .collect();
        all.extend(generated.files.iter().map(|f| FileEntry {
            path: f.path.clone(),
            sha256: String::new(),
            bytes: 0,
        }));
        all.sort_by(|a, b| a.path.cmp(&b.path));
        let interim = serde_json::json!({
            "schema": manifest::SCHEMA,
            "schema_version": manifest::SCHEMA_VERSION,
            "note": "interim manifest of a scatter-gen run in progress",
            "files": all,
        });
        let mut text = serde_json::to_string_pretty(&interim).unwrap_or_default();
        text.push('\n');
        write_atomic(&dir.join(MANIFEST), text.as_bytes())?;
    }

    // Phase 2: the files.
    for f in &generated.files {
        let path = dir.join(&f.path);
        if read_if_exists(&path)?.as_deref() == Some(f.bytes.as_slice()) {
            report.unchanged.push(f.path.clone());
        } else {
            write_atomic(&path, &f.bytes)?;
            report.written.push(f.path.clone());
        }
    }

    // Phase 3: our files that this run no longer produces.
    for p in &owned {
        if !new_paths.contains(p.as_str()) {
            let path = dir.join(p);
            match fs::remove_file(&path) {
                Ok(()) => report.removed.push(p.clone()),
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
                Err(e) => return Err(GenError::io(path, e)),
            }
        }
    }

    // Phase 4: the final manifest.
    let path = dir.join(MANIFEST);
    if read_if_exists(&path)?.as_deref() == Some(generated.manifest.as_slice()) {
        report.unchanged.push(MANIFEST.into());
    } else {
        write_atomic(&path, &generated.manifest)?;
        report.written.push(MANIFEST.into());
    }
    Ok(report)
}

/// Compares `dir` with `generated`: every generated file (manifest included) must exist with
/// the same bytes, and no file an earlier run generated may be left over. Foreign files are
/// ignored.
///
/// # Errors
///
/// [`GenError::Io`] when a file cannot be read.
pub fn check(dir: &Path, generated: &Generated) -> Result<Vec<Stale>, GenError> {
    let mut stale = Vec::new();
    for (p, bytes) in generated.all_files() {
        match read_if_exists(&dir.join(p))? {
            None => stale.push(Stale {
                path: p.to_owned(),
                why: "missing",
            }),
            Some(b) if b != bytes => stale.push(Stale {
                path: p.to_owned(),
                why: "differs",
            }),
            Some(_) => {}
        }
    }
    let new_paths: BTreeSet<&str> = generated.files.iter().map(|f| f.path.as_str()).collect();
    if let Ok(Some(old)) = owned_files(dir) {
        for f in old {
            if !new_paths.contains(f.path.as_str()) && dir.join(&f.path).exists() {
                stale.push(Stale {
                    path: f.path,
                    why: "no longer generated",
                });
            }
        }
    }
    Ok(stale)
}

/// `dir/path` for messages.
pub fn display_path(dir: &Path, path: &str) -> PathBuf {
    dir.join(path)
}
