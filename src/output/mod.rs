//! Output: ParaView snapshots, history, summary, pictures. Output never changes particles.

pub mod atomic;
pub mod checkpoint;
pub mod history;
pub mod picture;
pub mod summary;
pub mod vtk;
