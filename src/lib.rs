//! strike: smoothed particle hydrodynamics for solid bodies under impact, with the frictionless
//! particle contact of Vignjevic, De Vuyst & Campbell, "A Frictionless Contact Algorithm for
//! Meshless Methods", CMES 13(1) 35–48 (2006).
//!
//! Data flows one way: [`deck`] → [`setup`] → [`particles`] → each step ([`neighbors`] →
//! [`physics`] + [`contact`] + [`boundary`] → [`integrate`]) → [`output`].

// Errors carry their deck location and message by value; they are returned once per run, so
// their size does not matter.
#![allow(clippy::result_large_err)]

pub mod bench;
pub mod boundary;
pub mod case;
pub mod check;
pub mod contact;
pub mod deck;
pub mod error;
pub mod integrate;
pub mod kernel;
pub mod machine;
pub mod material;
pub mod mixing;
pub mod neighbors;
pub mod output;
pub mod particles;
pub mod physics;
pub mod ranks;
pub mod run;
pub mod setup;
pub mod simulation;
pub mod sweep;
pub mod tensor;
pub mod validate;

pub use error::{Error, Result};
