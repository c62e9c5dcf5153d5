//! Output: ParaView snapshots, history, summary, pictures. Output never changes particles.

pub mod picture;
pub mod vtk;
