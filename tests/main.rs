//! The integration tests, as one test binary (one link of the whole crate instead of one
//! per file). Each module is one former test file; shared helpers are in `common`.

mod common;

mod adapted;
mod axisym;
mod balloon;
mod bench_smoke;
mod branch;
mod chiral;
mod cli;
mod cli_branch;
mod cli_compare;
mod cli_run;
mod cli_spectrum;
mod critical_curve;
mod deflation;
mod effects_model;
mod export_rank_one;
mod fluid_volume;
mod fuzz;
mod hard_cases;
mod lanczos_cap;
mod layers;
mod linalg;
mod linear_buckling_plot;
mod meridian_analyses;
mod mesh_radius;
mod model_derivatives;
mod near_double;
mod newton;
mod one_point;
mod output;
mod ponding;
mod reliability;
mod saved_point;
mod scene_mesh_file;
mod scene_validation;
mod scenes_run;
mod sparse_path;
mod stability;
mod state_fields;
mod subgroup_path;
mod surface;
mod tension_field;
mod thesis;
mod thesis_curves;
