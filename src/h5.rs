//! Opening HDF5 files without HDF5's file locks.
//!
//! HDF5 (since 1.10) locks every file it opens with `flock`, on a descriptor opened without
//! close-on-exec. A child process started while a file is open (a study's batch script, a
//! test harness, `mpirun`) inherits that descriptor and so keeps the lock alive after mpfem
//! has closed the file; the next open of the same file then fails with "unable to lock file,
//! errno = 11". The lock would also keep ParaView from reading `results.h5` during a run.
//! Every mpfem file has exactly one writer (rank 0, or the one process of a serial run), and
//! checkpoints are renamed into place only once complete, so the locks protect nothing here:
//! mpfem opens all its files with locking off.

use std::path::Path;

fn builder() -> hdf5::FileBuilder {
    let mut b = hdf5::File::with_options();
    b.with_fapl(|p| p.file_locking(false));
    b
}

/// Open an existing file read-only.
///
/// # Errors
/// The HDF5 error when the file is missing or not an HDF5 file.
pub fn open(path: &Path) -> hdf5::Result<hdf5::File> {
    builder().open(path)
}

/// Open an existing file for reading and writing.
///
/// # Errors
/// The HDF5 error when the file is missing, read-only or not an HDF5 file.
pub fn open_rw(path: &Path) -> hdf5::Result<hdf5::File> {
    builder().open_rw(path)
}

/// Create a file, truncating one that exists.
///
/// # Errors
/// The HDF5 error when the file cannot be created.
pub fn create(path: &Path) -> hdf5::Result<hdf5::File> {
    builder().create(path)
}

/// Create a file with a user block of `size` bytes (a power of two ≥ 512) at its start, which
/// HDF5 leaves to the caller (a checkpoint keeps its whole-file checksum there).
///
/// # Errors
/// The HDF5 error when the file cannot be created.
pub fn create_with_userblock(path: &Path, size: u64) -> hdf5::Result<hdf5::File> {
    let mut b = builder();
    b.with_fcpl(|p| p.userblock(size));
    b.create(path)
}

#[cfg(test)]
mod tests {
    /// A file held open (and so locked by default) is still opened by a second handle, as an
    /// inherited descriptor in a child process would hold it; the data written is read back.
    #[test]
    fn a_file_open_elsewhere_can_still_be_opened() {
        let dir = std::env::temp_dir().join(format!("mpfem-h5-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("x.h5");
        {
            let f = super::create(&path).unwrap();
            f.new_dataset::<f64>().shape(3).create("v").unwrap().write_raw(&[1.0, 2.0, 3.0]).unwrap();
        }
        // an independent descriptor holding an exclusive flock, as HDF5's own lock would be
        let held = std::fs::File::open(&path).unwrap();
        held.lock().unwrap();
        if std::env::var_os("HDF5_USE_FILE_LOCKING").is_none() {
            assert!(hdf5::File::open(&path).is_err(), "a default open is refused while the lock is held");
        }
        let v: Vec<f64> = super::open(&path).unwrap().dataset("v").unwrap().read_raw().unwrap();
        assert_eq!(v, [1.0, 2.0, 3.0]);
        let f = super::open_rw(&path).unwrap();
        f.dataset("v").unwrap().write_raw(&[4.0, 5.0, 6.0]).unwrap();
        drop(f);
        let v: Vec<f64> = super::open(&path).unwrap().dataset("v").unwrap().read_raw().unwrap();
        assert_eq!(v, [4.0, 5.0, 6.0]);
        drop(held);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
