//! Runs scenes: drives the solver, samples histories, renders snapshots, writes the run
//! directory (local runs) or streams to the server (jobs).
