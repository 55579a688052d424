//! plyshell: nonlinear shell finite elements for layered protective garments.
//!
//! Data flows one way: scene file → model → solver → results → export.
//!
//! ```
//! use plyshell::{analysis, scene};
//! let text = include_str!("../garments/examples/roll_up.ron")
//!     .replace("increments: 40", "increments: 4")
//!     .replace("{\"end_moment\": 1.0}", "{\"end_moment\": 0.25}");
//! let sc = scene::parse("demo.ron", &text).expect("a valid scene");
//! let built = scene::build(&sc, "demo.ron", &text).expect("a buildable scene");
//! assert_eq!(built.model.n_nodes(), 49 * 5);
//! let summary = analysis::run(&sc, &built, &Default::default(), &mut |_| {}).expect("converges");
//! // A quarter of the end moment bends the strip into a quarter circle: tip lift L(1 − cos m)/m.
//! let uz = summary.monitors[0].values.last().expect("a value")[1];
//! let m = std::f64::consts::FRAC_PI_2;
//! assert!((uz - 12.0 * (1.0 - m.cos()) / m).abs() < 0.01 * uz);
//! ```

pub mod autodiff;
pub mod input;
pub mod element;
pub mod mesh;
pub mod material;
pub mod assembly;
pub mod model;
pub mod solver;
pub mod scene;
pub mod analysis;
pub mod analysis_auto;
pub mod analysis_sequence;
pub mod refine;
pub mod compare;
pub mod check;
pub mod io;
pub mod results;
pub mod bench;
pub mod study;
pub mod contact;
pub mod garment;
pub mod pattern;
pub mod budget;
pub mod cpu_time;
pub mod sizing;
pub mod fuzz;
pub mod mannequin;
