//! # anm — Asymptotic Numerical Method for shells in contact with friction
//!
//! High-order power-series continuation (one factorization per step) for
//! thin shells in contact with rigid obstacles and regularized friction, after
//! Béchet, Boudaoud, Lejeune, Potier-Ferry, *Résolution de problèmes de contact
//! avec la Méthode Asymptotique Numérique*, CFM 2009 ("the paper"; equation
//! numbers below are the paper's).
//!
//! - [`series`]: the generic ANM engine (Taylor arithmetic, arclength
//!   continuation, Taylor series in time for index-1 DAEs, Padé, statistics).
//! - [`contact`]: regularized contact law (eq. 3) and power friction law
//!   (eqs. 5, 6, 11).
//! - [`model`]: the canonical problems assembled from a scene.
//! - [`scene`]: TOML scene files, validated into a model.
//! - [`output`]: CSV, JSON, plots.

// `!(x > y)` is used on purpose: it is true for NaN, which must fail the check.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod contact;
pub mod error;
pub mod fe;
pub mod linalg;
pub mod mesh;
pub mod model;
pub mod output;
pub mod reference;
pub mod run;
pub mod scene;
pub mod series;
pub mod shell;
pub mod study;

pub use error::{Error, Result};
