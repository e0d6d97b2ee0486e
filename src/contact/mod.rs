//! Contact with rigid obstacles: the regularized normal law (paper eq. 3),
//! the regularized power friction law (eqs. 5, 6, 11), analytic obstacles
//! (gap and normal) and the contact candidate search.

pub mod friction;
pub mod log_reaction;
pub mod motion;
pub mod normal;
pub mod obstacle;
pub mod search;

pub use friction::FrictionLaw;
pub use motion::Motion;
pub use normal::NormalLaw;
pub use obstacle::Obstacle;
