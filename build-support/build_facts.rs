// Shared by the build scripts of `fracture-server` and `fracture-worker` (`include!`d):
// the git commit (`FRACTURE_GIT_COMMIT` if the builder sets it, else `git rev-parse HEAD`
// when the sources are a git checkout) and the Cargo profile, as `rustc-env`. Nothing fails
// when git is missing: the commit is then unknown.

use std::process::Command;

fn git(args: &[&str]) -> Option<String> {
    let out = Command::new("git").args(args).output().ok()?;
    if !out.status.success() {
        return None;
    }
    let s = String::from_utf8(out.stdout).ok()?.trim().to_string();
    (!s.is_empty()).then_some(s)
}

/// Emit `FRACTURE_GIT_COMMIT` and `FRACTURE_BUILD_PROFILE` for the crate being built.
fn emit_build_facts() {
    println!("cargo:rerun-if-env-changed=FRACTURE_GIT_COMMIT");
    if let Ok(p) = std::env::var("PROFILE") {
        println!("cargo:rustc-env=FRACTURE_BUILD_PROFILE={p}");
    }
    let commit = std::env::var("FRACTURE_GIT_COMMIT")
        .ok()
        .filter(|c| !c.is_empty())
        .or_else(|| git(&["rev-parse", "HEAD"]));
    if let Some(c) = commit {
        println!("cargo:rustc-env=FRACTURE_GIT_COMMIT={c}");
    }
    // Rebuild when HEAD moves (a commit, a checkout), in a worktree too.
    for path in [
        git(&["rev-parse", "--git-path", "HEAD"]),
        git(&["rev-parse", "--symbolic-full-name", "HEAD"])
            .and_then(|r| git(&["rev-parse", "--git-path", &r])),
    ]
    .into_iter()
    .flatten()
    .filter(|p| std::path::Path::new(p).exists())
    {
        println!("cargo:rerun-if-changed={path}");
    }
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=../build-support/build_facts.rs");
}
