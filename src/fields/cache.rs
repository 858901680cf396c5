//! The disk cache of baked fields: a folder of the user's own (the platform's cache directory,
//! never the shared temporary folder), files written atomically (a new temporary file, then a
//! rename, so a reader never sees half a file and no symlink is followed), read only when they
//! are regular files of exactly the size the bake would write, and trusted only when their grid
//! is the one the mesh and settings would bake. A file's name hashes the mesh, the settings, the
//! format version and the crate's version; a change to the baker between releases is not in it,
//! so whoever changes the baker deletes the folder before measuring.

use std::fs::{self, File, OpenOptions};
use std::io::{self, Read, Write};
use std::path::{Path, PathBuf};

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
        fs::remove_dir_all(&folder).unwrap();
    }
}
