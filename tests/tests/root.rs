//! The lavapipe integration tests: one binary, one module per subject. Every test that touches the GPU
//! uses `bounce_tests::TestGpu`, which fails the test on any validation message.

mod bvh;
mod cdf;
mod cli;
mod direct;
mod dprsm;
mod end_balls;
mod fuzz_corpus;
mod graph;
mod images;

mod layout;
mod lightmaps;
mod present;
mod progressive;
mod psm;
mod reads;
mod realtime;
mod reference;
mod ris;
mod stress;
mod validation;
mod visibility;
mod voxelize;
mod vpl;
