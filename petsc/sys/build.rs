//! Finds the system PETSc with pkg-config (`PETSc.pc` of Debian's `libpetsc-real-dev`) and the
//! MPI headers it was built against, and generates the bindings of the part mpfem uses.

use std::path::PathBuf;
use std::process::Command;

fn main() {
    println!("cargo:rerun-if-changed=wrapper.h");
    println!("cargo:rerun-if-env-changed=PETSC_DIR");
    let petsc = pkg_config::Config::new().atleast_version("3.18").probe("PETSc").unwrap_or_else(|e| {
        panic!("PETSc ≥ 3.18 not found by pkg-config ({e}); install it with `bash scripts/setup.sh` (Debian: libpetsc-real-dev), or build mpfem without the `petsc` feature")
    });
    let mut include: Vec<PathBuf> = petsc.include_paths.clone();
    // PETSc's headers include <mpi.h>, which Debian keeps under Open MPI's own folder
    include.extend(mpi_include_dirs());
    let mut builder = bindgen::Builder::default()
        .header("wrapper.h")
        .allowlist_function("(Petsc|Mat|Vec|KSP|PC)[A-Za-z0-9_]*")
        .allowlist_function("MPI_Comm_rank|MPI_Comm_size")
        .allowlist_var("PETSC_COMM_WORLD|PETSC_DECIDE|PETSC_DETERMINE|PETSC_DEFAULT")
        .allowlist_var("MAT(AIJ|MPIAIJ|SEQAIJ)|KSP(CG|GMRES|PREONLY)|PC(LU|CHOLESKY|GAMG|JACOBI|NONE)|MATSOLVERMUMPS")
        .allowlist_type("(Mat|Vec|KSP|PC)(Option|AssemblyType|ConvergedReason|FailedReason|FactorError|Structure)?|PetscErrorType|InsertMode|ScatterMode|NormType|PetscBool")
        .blocklist_function(".*(Fortran|_Private|Viewer).*")
        .rustified_enum("PetscBool|PetscErrorType|PetscErrorType|InsertMode|ScatterMode|NormType|MatAssemblyType|MatOption|KSPConvergedReason|PCFailedReason|MatFactorError")
        .derive_debug(true)
        .layout_tests(false)
        .generate_comments(false)
        .parse_callbacks(Box::new(bindgen::CargoCallbacks::new()));
    for dir in &include {
        builder = builder.clang_arg(format!("-I{}", dir.display()));
    }
    let bindings = builder.generate().expect("bindgen over PETSc's petscksp.h");
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("OUT_DIR"));
    bindings.write_to_file(out.join("bindings.rs")).expect("write bindings.rs");
}

/// The MPI PETSc was built against, linked (PETSc's own `.pc` names only PETSc; the MPI
/// calls of the wrapper need libmpi) and its include folders: pkg-config's `ompi-c` (Open
/// MPI, Debian's) or `mpich`, else what `mpicc --showme:incdirs` names.
fn mpi_include_dirs() -> Vec<PathBuf> {
    for name in ["ompi-c", "mpich"] {
        if let Ok(lib) = pkg_config::Config::new().probe(name) {
            return lib.include_paths;
        }
    }
    println!("cargo:rustc-link-lib=mpi");
    if let Ok(o) = Command::new("mpicc").arg("--showme:incdirs").output() {
        if o.status.success() {
            return String::from_utf8_lossy(&o.stdout).split_whitespace().map(PathBuf::from).collect();
        }
    }
    Vec::new()
}
