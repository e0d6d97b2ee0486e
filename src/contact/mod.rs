//! Contact with rigid obstacles: the regularized normal law (paper eq. 3) and
//! the regularized power friction law (eqs. 5, 6, 11).

pub mod friction;
pub mod normal;

pub use friction::FrictionLaw;
pub use normal::NormalLaw;
