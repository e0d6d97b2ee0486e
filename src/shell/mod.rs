//! 3D shell with a director-difference vector, EAS and ANS (DESIGN §3): the
//! kinematics (strain exactly quadratic in the unknowns), the 3D St
//! Venant–Kirchhoff law, the 4-node element, its internal force along an ANM
//! series, and the assembled model that the ANM engine continues.

pub mod chart;
pub mod element;
pub mod friction_dae;
pub mod friction_pair;
pub mod geometric_map;
pub mod implicit_step;
pub mod kinematics;
pub mod material;
pub mod model;
pub mod ramp;
pub mod series;
pub mod stability;
pub mod time_path;

pub use element::ShellElement;
pub use material::Material;
pub use model::{FollowerCouple, ShellModel};
