//! Build facts for the run summary's provenance (`summary.provenance.solver_commit`): the
//! git commit and the Cargo profile, as the server's build script finds them.

include!("../build-support/build_facts.rs");

fn main() {
    emit_build_facts();
}
