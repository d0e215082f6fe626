//! Build facts for `GET /api/v1/version`: the git commit (`FRACTURE_GIT_COMMIT` if the
//! builder sets it, else `git rev-parse HEAD` when the sources are a git checkout) and the
//! Cargo profile. Nothing fails when git is missing: the commit is then unknown.

include!("../build-support/build_facts.rs");

fn main() {
    emit_build_facts();
}
