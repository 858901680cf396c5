//! The disk cache of baked fields: a folder of the user's own (the platform's cache directory,
//! never the shared temporary folder), files written atomically (a new temporary file, then a
//! rename, so a reader never sees half a file and no symlink is followed), read only when they
//! are regular files of exactly the size the bake would write, and trusted only when their grid
//! is the one the mesh and settings would bake. A file's name hashes the mesh, the settings, the
//! format version and the crate's version; a change to the baker between releases is not in it,
//! so whoever changes the baker deletes the folder before measuring.
//!
//! The folder is kept under a size: after each write the files used longest ago (a read marks a
//! file used) are deleted until the rest fit, so a game that bakes many meshes, or many releases
//! of it, does not fill the user's disk.

use std::fs::{self, File, OpenOptions};
use std::io::{self, Read, Write};
use std::path::{Path, PathBuf};
use std::time::{Duration, SystemTime};

use super::baker::BakeGrid;
use super::format::AoFieldData;

/// The platform's per-user cache directory, joined with `bevy_dynamic_ao/fields`:
/// `$XDG_CACHE_HOME` or `~/.cache` on Linux and other Unix systems, `~/Library/Caches` on macOS,
/// `%LOCALAPPDATA%` on Windows. `None` where the platform names none (the plugin then bakes
/// every run).
pub fn default_folder() -> Option<PathBuf> {
    let env = |name| {
        std::env::var_os(name)
            .map(PathBuf::from)
            .filter(|p| p.is_absolute())
    };
    let base = if cfg!(windows) {
        env("LOCALAPPDATA")
    } else if cfg!(target_os = "macos") {
        env("HOME").map(|home| home.join("Library").join("Caches"))
    } else {
        env("XDG_CACHE_HOME").or_else(|| env("HOME").map(|home| home.join(".cache")))
    };
    base.map(|base| base.join("bevy_dynamic_ao").join("fields"))
}

/// Why a cached file was not used.
#[derive(Debug)]
pub(crate) enum CacheMiss {
    /// No file by that name: bake.
    Absent,
    /// A file that is not to be read or trusted; the message says why.
    Rejected(String),
}

/// The field cached at `path`, if it is a regular file (not a symlink) of exactly the size a
/// field on `grid` takes, with a valid checksum, and its grid is `grid`.
pub(crate) fn read(path: &Path, grid: &BakeGrid) -> Result<AoFieldData, CacheMiss> {
    let reject = |why: String| Err(CacheMiss::Rejected(why));
    let link = match fs::symlink_metadata(path) {
        Ok(metadata) => metadata,
        Err(error) if error.kind() == io::ErrorKind::NotFound => return Err(CacheMiss::Absent),
        Err(error) => return reject(error.to_string()),
    };
    if !link.file_type().is_file() {
        return reject("not a regular file".into());
    }
    let expected = AoFieldData::file_size(grid.resolution);
    if link.len() != expected as u64 {
        return reject(format!(
            "{} bytes where this mesh's field takes {expected}",
            link.len()
        ));
    }
    let mut file = File::open(path).map_err(|e| CacheMiss::Rejected(e.to_string()))?;
    // The file opened must be the one looked at (not swapped for a link in between).
    let opened = file
        .metadata()
        .map_err(|e| CacheMiss::Rejected(e.to_string()))?;
    if !same_file(&link, &opened) {
        return reject("it changed while it was opened".into());
    }
    let mut bytes = Vec::with_capacity(expected);
    Read::by_ref(&mut file)
        .take(expected as u64 + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| CacheMiss::Rejected(e.to_string()))?;
    if bytes.len() != expected {
        return reject(format!("{} bytes read, {expected} expected", bytes.len()));
    }
    let field = AoFieldData::from_bytes(&bytes).map_err(|e| CacheMiss::Rejected(e.to_string()))?;
    if !grid.matches(&field) {
        return reject("its grid is not the one this mesh bakes".into());
    }
    // Marks the file used, so the size limit deletes others first. Where the platform does not
    // let a read handle do it (Windows), files go in the order they were written.
    let _ = file.set_modified(SystemTime::now());
    Ok(field)
}

#[cfg(unix)]
fn same_file(a: &fs::Metadata, b: &fs::Metadata) -> bool {
    use std::os::unix::fs::MetadataExt;
    a.dev() == b.dev() && a.ino() == b.ino() && b.file_type().is_file()
}

#[cfg(not(unix))]
fn same_file(a: &fs::Metadata, b: &fs::Metadata) -> bool {
    b.file_type().is_file() && a.len() == b.len()
}

/// Writes `field` to `path` atomically: into a new file beside it (created exclusively, so an
/// existing file or symlink of that name is never opened), then renamed over `path` (which
/// replaces a symlink there instead of writing through it). The folder is created readable by
/// the user alone where the platform has modes.
pub(crate) fn write(path: &Path, field: &AoFieldData) -> io::Result<()> {
    let folder = path
        .parent()
        .ok_or_else(|| io::Error::other("the cache path has no folder"))?;
    create_private_folder(folder)?;
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos());
    let temporary = folder.join(format!(".{}-{nanos}.partial", std::process::id()));
    let written = (|| {
        let mut options = OpenOptions::new();
        options.write(true).create_new(true);
        #[cfg(unix)]
        {
            use std::os::unix::fs::OpenOptionsExt;
            options.mode(0o600);
        }
        let mut file = options.open(&temporary)?;
        file.write_all(&field.to_bytes())?;
        file.sync_all()?;
        fs::rename(&temporary, path)
    })();
    if written.is_err() {
        let _ = fs::remove_file(&temporary);
    }
    written
}

/// The extension of a cached field's file; [`prune`] deletes no other file but its own
/// leftovers.
pub(crate) const FIELD_EXTENSION: &str = "aofield";

/// A `.partial` file this old was left by a process that stopped while writing it.
const ABANDONED_AFTER: Duration = Duration::from_secs(3600);

/// What [`prune`] deleted.
#[derive(Debug, Default, PartialEq, Eq)]
pub(crate) struct Pruned {
    /// Fields deleted.
    pub files: usize,
    /// Their bytes.
    pub bytes: u64,
}

/// Deletes the fields in `folder` used longest ago (by modification time, which [`read`] moves)
/// until the rest take at most `max_bytes`, never `keep` (the field just written, kept even when
/// it alone is larger), and temporary files abandoned over an hour ago. Symlinks, folders and
/// files of other names are left alone; a file another process deleted first is skipped.
pub(crate) fn prune(folder: &Path, max_bytes: u64, keep: &Path) -> io::Result<Pruned> {
    let now = SystemTime::now();
    let mut fields = Vec::new();
    for entry in fs::read_dir(folder)? {
        let Ok(entry) = entry else { continue };
        let path = entry.path();
        let Ok(metadata) = fs::symlink_metadata(&path) else {
            continue;
        };
        if !metadata.file_type().is_file() {
            continue;
        }
        let modified = metadata.modified().unwrap_or(SystemTime::UNIX_EPOCH);
        let name = entry.file_name();
        let name = name.to_string_lossy();
        if name.starts_with('.') && name.ends_with(".partial") {
            if now
                .duration_since(modified)
                .is_ok_and(|age| age > ABANDONED_AFTER)
            {
                let _ = fs::remove_file(&path);
            }
        } else if path.extension().is_some_and(|e| e == FIELD_EXTENSION) {
            fields.push((modified, metadata.len(), path));
        }
    }
    let mut total: u64 = fields.iter().map(|(_, len, _)| len).sum();
    // Oldest first; ties by name, so the order does not depend on the folder's listing.
    fields.sort();
    let mut pruned = Pruned::default();
    for (_, len, path) in fields {
        if total <= max_bytes {
            break;
        }
        if path == keep {
            continue;
        }
        match fs::remove_file(&path) {
            Ok(()) => {
                pruned.files += 1;
                pruned.bytes += len;
                total -= len;
            }
            Err(error) if error.kind() == io::ErrorKind::NotFound => total -= len,
            Err(error) => return Err(error),
        }
    }
    Ok(pruned)
}

/// Creates `folder` (and its parents) if needed, new folders with mode 0700 on Unix, and checks
/// that it is a real folder that no one else may write to.
fn create_private_folder(folder: &Path) -> io::Result<()> {
    let mut builder = fs::DirBuilder::new();
    builder.recursive(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::DirBuilderExt;
        builder.mode(0o700);
    }
    builder.create(folder)?;
    let metadata = fs::symlink_metadata(folder)?;
    if !metadata.file_type().is_dir() {
        return Err(io::Error::other(format!(
            "{} is not a folder (a symlink?)",
            folder.display()
        )));
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        if metadata.permissions().mode() & 0o022 != 0 {
            return Err(io::Error::other(format!(
                "{} may be written by other users; the cache is not used",
                folder.display()
            )));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fields::baker::{BakeSettings, FieldReach, bake};
    use crate::geometry::triangles::TriangleScene;
    use bevy::math::{Affine3A, primitives::Cuboid};

    fn cube() -> Vec<crate::geometry::triangles::Triangle> {
        let mut scene = TriangleScene::default();
        scene.add_mesh(&Cuboid::new(1.0, 1.0, 1.0).into(), Affine3A::IDENTITY);
        scene.triangles
    }

    fn settings() -> BakeSettings {
        BakeSettings {
            resolution: 4,
            rays: 16,
            reach: FieldReach::Distance {
                reach: 0.5,
                near: 0.25,
            },
            ..Default::default()
        }
    }

    fn folder(name: &str) -> PathBuf {
        let folder = std::env::temp_dir().join(format!(
            "bevy_dynamic_ao_cache_test_{name}_{}",
            std::process::id()
        ));
        let _ = fs::remove_dir_all(&folder);
        folder
    }

    #[test]
    fn a_written_field_reads_back_and_only_for_its_own_mesh() {
        let folder = folder("roundtrip");
        let path = folder.join("cube.aofield");
        let field = bake(cube(), &settings(), &|_, _| {}).unwrap();
        let grid = BakeGrid::plan(&cube(), &settings()).unwrap();
        assert!(matches!(read(&path, &grid), Err(CacheMiss::Absent)));
        write(&path, &field).unwrap();
        assert_eq!(read(&path, &grid).unwrap(), field);
        // The same file claimed for another mesh (a bigger box) is not trusted.
        let big: Vec<_> = cube()
            .into_iter()
            .map(|mut t| {
                t.vertices = t.vertices.map(|v| v * 2.0);
                t
            })
            .collect();
        let other = BakeGrid::plan(&big, &settings()).unwrap();
        assert!(matches!(read(&path, &other), Err(CacheMiss::Rejected(_))));
        // No temporary file is left behind.
        assert_eq!(fs::read_dir(&folder).unwrap().count(), 1);
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = fs::metadata(&folder).unwrap().permissions().mode();
            assert_eq!(
                mode & 0o077,
                0,
                "the cache folder is the user's alone: {mode:o}"
            );
        }
        fs::remove_dir_all(&folder).unwrap();
    }

    #[test]
    fn oversized_and_forged_files_are_rejected() {
        let folder = folder("forged");
        let path = folder.join("cube.aofield");
        let grid = BakeGrid::plan(&cube(), &settings()).unwrap();
        create_private_folder(&folder).unwrap();
        // Larger than the field could be: rejected without reading it.
        fs::write(
            &path,
            vec![0u8; AoFieldData::file_size(grid.resolution) * 4],
        )
        .unwrap();
        assert!(matches!(read(&path, &grid), Err(CacheMiss::Rejected(_))));
        // The right size but not a field (bad magic, bad checksum).
        fs::write(&path, vec![7u8; AoFieldData::file_size(grid.resolution)]).unwrap();
        assert!(matches!(read(&path, &grid), Err(CacheMiss::Rejected(_))));
        fs::remove_dir_all(&folder).unwrap();
    }

    /// A file of `len` bytes at `path`, last modified `age_s` seconds ago.
    fn aged_file(path: &Path, len: usize, age_s: u64) {
        fs::write(path, vec![1u8; len]).unwrap();
        let when = SystemTime::now() - Duration::from_secs(age_s);
        File::options()
            .write(true)
            .open(path)
            .unwrap()
            .set_modified(when)
            .unwrap();
    }

    fn names(folder: &Path) -> Vec<String> {
        let mut names: Vec<_> = fs::read_dir(folder)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn pruning_deletes_the_fields_used_longest_ago_and_nothing_else() {
        let folder = folder("prune");
        create_private_folder(&folder).unwrap();
        for (name, age_s) in [("a", 400), ("b", 300), ("c", 200), ("d", 100)] {
            aged_file(&folder.join(format!("{name}.aofield")), 1000, age_s);
        }
        // Not fields: a user's file, a write in progress and one abandoned two hours ago.
        aged_file(&folder.join("notes.txt"), 5000, 500);
        aged_file(&folder.join(".7-1.partial"), 5000, 10);
        aged_file(&folder.join(".7-2.partial"), 5000, 7200);
        let pruned = prune(&folder, 2000, &folder.join("d.aofield")).unwrap();
        assert_eq!(
            pruned,
            Pruned {
                files: 2,
                bytes: 2000
            }
        );
        assert_eq!(
            names(&folder),
            [".7-1.partial", "c.aofield", "d.aofield", "notes.txt"]
        );
        // Under the limit nothing goes; at zero all but the field just written go.
        assert_eq!(
            prune(&folder, 2000, &folder.join("d.aofield"))
                .unwrap()
                .files,
            0
        );
        assert_eq!(
            prune(&folder, 0, &folder.join("c.aofield")).unwrap().files,
            1
        );
        assert_eq!(names(&folder), [".7-1.partial", "c.aofield", "notes.txt"]);
        fs::remove_dir_all(&folder).unwrap();
    }

    // Windows does not let a read handle set a file's time (see `read`).
    #[cfg(unix)]
    #[test]
    fn reading_a_field_keeps_it_from_pruning() {
        let folder = folder("prune_read");
        let field = bake(cube(), &settings(), &|_, _| {}).unwrap();
        let grid = BakeGrid::plan(&cube(), &settings()).unwrap();
        let len = AoFieldData::file_size(grid.resolution) as u64;
        let (old, newer, new) = (
            folder.join("old.aofield"),
            folder.join("newer.aofield"),
            folder.join("new.aofield"),
        );
        for (path, age_s) in [(&old, 300), (&newer, 200)] {
            write(path, &field).unwrap();
            File::options()
                .write(true)
                .open(path)
                .unwrap()
                .set_modified(SystemTime::now() - Duration::from_secs(age_s))
                .unwrap();
        }
        // The oldest file is read: it is now the one used last but for the new one.
        assert_eq!(read(&old, &grid).unwrap(), field);
        write(&new, &field).unwrap();
        assert_eq!(prune(&folder, 2 * len, &new).unwrap().files, 1);
        assert_eq!(names(&folder), ["new.aofield", "old.aofield"]);
        fs::remove_dir_all(&folder).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn symlinks_are_neither_read_nor_written_through() {
        let folder = folder("symlink");
        create_private_folder(&folder).unwrap();
        let victim = folder.join("victim.txt");
        fs::write(&victim, b"keep me").unwrap();
        let path = folder.join("cube.aofield");
        std::os::unix::fs::symlink(&victim, &path).unwrap();
        let grid = BakeGrid::plan(&cube(), &settings()).unwrap();
        assert!(matches!(read(&path, &grid), Err(CacheMiss::Rejected(_))));
        let field = bake(cube(), &settings(), &|_, _| {}).unwrap();
        write(&path, &field).unwrap();
        assert_eq!(fs::read(&victim).unwrap(), b"keep me");
        assert!(fs::symlink_metadata(&path).unwrap().file_type().is_file());
        assert_eq!(read(&path, &grid).unwrap(), field);
        // A folder others may write to is not used.
        use std::os::unix::fs::PermissionsExt;
        fs::set_permissions(&folder, fs::Permissions::from_mode(0o777)).unwrap();
        assert!(write(&path, &field).is_err());
        // Pruning deletes neither a link nor what it points at.
        fs::set_permissions(&folder, fs::Permissions::from_mode(0o700)).unwrap();
        fs::remove_file(&path).unwrap();
        std::os::unix::fs::symlink(&victim, &path).unwrap();
        assert_eq!(
            prune(&folder, 0, &folder.join("x.aofield")).unwrap().files,
            0
        );
        assert_eq!(fs::read(&victim).unwrap(), b"keep me");
        assert!(
            fs::symlink_metadata(&path)
                .unwrap()
                .file_type()
                .is_symlink()
        );
        fs::remove_dir_all(&folder).unwrap();
    }
}
