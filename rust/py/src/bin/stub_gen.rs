//! Writes the type stubs of `gagekit._core` (one `.pyi` per domain submodule) from the
//! bindings' Rust signatures and doc comments: `cargo run -p gagekit-py --features stubs --bin stub_gen [ROOT]`,
//! where ROOT is the folder that holds the `gagekit` package (default: the repository's
//! `python/`). tests/test_stubs.py runs it into a temporary folder and compares.

fn main() -> pyo3_stub_gen::Result<()> {
    let root = std::env::args().nth(1);
    _core::stub_info(root.map(std::path::PathBuf::from))?.generate()?;
    Ok(())
}
