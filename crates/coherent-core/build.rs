//! Compiles the project's own benchmark (`benchmark/` at the repository root) into the
//! crate: every `benchmark/tasks/<scene>/*.json` and `benchmark/subset-40.txt`, found
//! here so that adding a task needs no code change.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../benchmark");
    println!("cargo:rerun-if-changed={}", root.display());
    let mut files: Vec<PathBuf> = Vec::new();
    if let Ok(scenes) = std::fs::read_dir(root.join("tasks")) {
        for scene in scenes.flatten() {
            let Ok(entries) = std::fs::read_dir(scene.path()) else {
                continue;
            };
            files.extend(
                entries
                    .flatten()
                    .map(|e| e.path())
                    .filter(|p| p.extension().is_some_and(|x| x == "json")),
            );
        }
    }
    files.sort();
    let mut out = String::from("/// Every benchmark task file: (path under `benchmark/`, text).\n");
    out.push_str("pub const FILES: &[(&str, &str)] = &[\n");
    for f in &files {
        let rel = f.strip_prefix(&root).expect("a file under benchmark/");
        writeln!(
            out,
            "    ({:?}, include_str!({:?})),",
            rel.display().to_string(),
            f.display().to_string()
        )
        .expect("write to a String");
    }
    out.push_str("];\n");
    let subset = root.join("subset-40.txt");
    out.push_str("/// `benchmark/subset-40.txt`: `scene task_id` lines.\n");
    if subset.exists() {
        writeln!(
            out,
            "pub const SUBSET_40: &str = include_str!({:?});",
            subset.display().to_string()
        )
        .expect("write to a String");
    } else {
        out.push_str("pub const SUBSET_40: &str = \"\";\n");
    }
    let dest = PathBuf::from(std::env::var("OUT_DIR").expect("OUT_DIR set by cargo"))
        .join("benchmark_files.rs");
    std::fs::write(dest, out).expect("write benchmark_files.rs");
}
