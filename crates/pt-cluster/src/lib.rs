//! Rendering on a cluster. A render of S samples per pixel is split into N shares of
//! interleaved sample indices (`pt render SCENE --part K/N` takes samples K-1, K-1+N, ...);
//! each process writes a *part file* ([`part`]): the exact sums of its samples (see
//! `pt_render::film::exact`) and what identifies the render they belong to. `pt merge` checks
//! that a set of parts is one whole render ([`part::check_set`]) and adds them; the sums are
//! integers, so the merged image is bit-identical to the render on one machine.
//!
//! [`slurm`] writes (and submits) the Slurm job array that runs the parts, with a merge job
//! that waits for the whole array, and reports which parts are done. The crate knows nothing
//! of rendering: the sums inside a part are opaque bytes here.
//!
//! The commands, what is exact and why, and a Kubernetes manifest for the same scheme are in
//! this crate's README.md.

pub mod part;
pub mod slurm;
