//! VTK XML PolyData snapshots (.vtp, raw appended binary) and the .pvd time series.
