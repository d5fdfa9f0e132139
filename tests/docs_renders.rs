//! The renders in docs/render are what `coherent render --plan` writes today, byte for
//! byte, with the command docs/physics.md gives (regenerate one by running it with
//! `-o docs/render/envN.svg`).

mod common;

use common::{coherent, released, scratch, show, utf8};

#[test]
fn each_render_in_the_docs_is_what_the_command_writes() {
    let dir = scratch("docs-renders");
    let docs = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/render");
    for (scene, task) in [
        ("env0", "14"),
        ("env1", "15"),
        ("env2", "13"),
        ("env3", "13"),
    ] {
        let tasks = released().join(format!("{scene}.json"));
        let out = dir.join(format!("{scene}.svg"));
        let run = coherent(&[
            "render",
            utf8(&tasks),
            "--task",
            task,
            "--plan",
            "-o",
            utf8(&out),
        ]);
        assert_eq!(run.status.code(), Some(0), "{}", show(&run));
        let written = std::fs::read(&out).expect("the render");
        let kept = std::fs::read(docs.join(format!("{scene}.svg"))).expect("the docs' render");
        assert!(
            written == kept,
            "docs/render/{scene}.svg is not what `coherent render {scene}.json --task {task} --plan` writes: regenerate it"
        );
    }
}
