//! VTK XML PolyData snapshots (.vtp, raw appended binary) and the .pvd time series.
//!
//! A snapshot holds the real particles (`0..n_real`, never ghosts) as points with one vertex
//! cell each, so ParaView shows them directly. All arrays live in one `<AppendedData
//! encoding="raw">` block: for each array a little-endian UInt64 byte count, then the data.
//! Points are 3D (z = 0 in 2D); the time is stored as the FieldData array `TIME`.

// `crate::Error` is large (its `Deck` variant); boxing it is the error module's decision.
#![allow(clippy::result_large_err)]

use std::fs::File;
use std::io::{BufWriter, Write};
use std::ops::Range;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::output::atomic;
use crate::particles::Particles;
use crate::tensor;

/// VTK scalar type of an array.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Ty {
    Int32,
    Int64,
    Float64,
}

impl Ty {
    fn name(self) -> &'static str {
        match self {
            Ty::Int32 => "Int32",
            Ty::Int64 => "Int64",
            Ty::Float64 => "Float64",
        }
    }

    fn size(self) -> usize {
        match self {
            Ty::Int32 => 4,
            Ty::Int64 | Ty::Float64 => 8,
        }
    }
}

/// Appends the tuple of entry `i` to the byte buffer, little-endian.
type Fill<'a> = Box<dyn Fn(usize, &mut Vec<u8>) + 'a>;

/// One appended array: its XML description and how to produce its bytes.
struct Array<'a> {
    name: &'static str,
    ty: Ty,
    ncomp: usize,
    /// Number of tuples.
    len: usize,
    fill: Fill<'a>,
}

impl Array<'_> {
    fn byte_count(&self) -> u64 {
        (self.len * self.ncomp * self.ty.size()) as u64
    }
}

fn f64s(buf: &mut Vec<u8>, values: &[f64]) {
    for v in values {
        buf.extend_from_slice(&v.to_le_bytes());
    }
}

fn float_array<'a>(
    name: &'static str,
    len: usize,
    ncomp: usize,
    fill: impl Fn(usize, &mut Vec<u8>) + 'a,
) -> Array<'a> {
    Array {
        name,
        ty: Ty::Float64,
        ncomp,
        len,
        fill: Box::new(fill),
    }
}

fn scalar<'a>(name: &'static str, values: &'a [f64], len: usize) -> Array<'a> {
    float_array(name, len, 1, move |i, b| {
        b.extend_from_slice(&values[i].to_le_bytes())
    })
}

/// The full 3×3 deviatoric stress of particle `i`, row-major; in 2D plane strain the z row and
/// column are zero except S_zz = −(S_xx + S_yy).
pub fn deviatoric_stress3<const D: usize>(particles: &Particles<D>, i: usize) -> [f64; 9] {
    let s = &particles.s[i].full();
    let mut out = [0.0; 9];
    for r in 0..D.min(3) {
        for c in 0..D.min(3) {
            out[3 * r + c] = s[(r, c)];
        }
    }
    if D == 2 {
        out[8] = tensor::out_of_plane(s);
    }
    out
}

/// Point-data arrays, in file order: (name, VTK type, components).
pub const POINT_DATA: [(&str, &str, usize); 14] = [
    ("body", "Int32", 1),
    ("id", "Int32", 1),
    ("velocity", "Float64", 3),
    ("pressure", "Float64", 1),
    ("density", "Float64", 1),
    ("internal_energy", "Float64", 1),
    ("deviatoric_stress", "Float64", 9),
    ("von_mises", "Float64", 1),
    ("plastic_strain", "Float64", 1),
    ("damage", "Float64", 1),
    ("smoothing_length", "Float64", 1),
    ("contact_force", "Float64", 3),
    ("mass", "Float64", 1),
    ("sound_speed", "Float64", 1),
];

/// The point data of particles `range` (entry i of an array is particle range.start + i).
fn point_data<'a, const D: usize>(p: &'a Particles<D>, range: Range<usize>) -> Vec<Array<'a>> {
    let (n, o) = (range.len(), range.start);
    let end = range.end;
    let at = move |values: &'a [f64]| &values[o..end];
    vec![
        Array {
            name: "body",
            ty: Ty::Int32,
            ncomp: 1,
            len: n,
            fill: Box::new(move |i, b| b.extend_from_slice(&(p.body[o + i] as i32).to_le_bytes())),
        },
        Array {
            name: "id",
            ty: Ty::Int32,
            ncomp: 1,
            len: n,
            fill: Box::new(move |i, b| b.extend_from_slice(&(p.id[o + i] as i32).to_le_bytes())),
        },
        float_array("velocity", n, 3, move |i, b| f64s(b, &p.velocity3(o + i))),
        scalar("pressure", at(&p.p), n),
        scalar("density", at(&p.rho), n),
        scalar("internal_energy", at(&p.e), n),
        float_array("deviatoric_stress", n, 9, move |i, b| {
            f64s(b, &deviatoric_stress3(p, o + i))
        }),
        float_array("von_mises", n, 1, move |i, b| {
            b.extend_from_slice(&tensor::von_mises(&p.s[o + i].full()).to_le_bytes())
        }),
        scalar("plastic_strain", at(&p.eps_p), n),
        scalar("damage", at(&p.damage), n),
        scalar("smoothing_length", at(&p.h), n),
        float_array("contact_force", n, 3, move |i, b| {
            f64s(b, &crate::particles::to3(&p.contact_force[o + i]))
        }),
        scalar("mass", at(&p.m), n),
        scalar("sound_speed", at(&p.c), n),
    ]
}

fn data_array_xml(xml: &mut String, indent: &str, a: &Array, offset: u64, tuples_attr: bool) {
    use std::fmt::Write as _;
    let _ = write!(
        xml,
        "{indent}<DataArray type=\"{}\" Name=\"{}\"",
        a.ty.name(),
        a.name
    );
    if a.ncomp != 1 {
        let _ = write!(xml, " NumberOfComponents=\"{}\"", a.ncomp);
    }
    if tuples_attr {
        let _ = write!(xml, " NumberOfTuples=\"{}\"", a.len);
    }
    let _ = writeln!(xml, " format=\"appended\" offset=\"{offset}\"/>");
}

/// Size in bytes of a snapshot of `n` particles: the point data of [`POINT_DATA`], the points
/// (3 × f64), the vertex connectivity and offsets (2 × i64), each array's 8-byte count, and a
/// few kB of XML.
pub fn snapshot_bytes(n: usize) -> u64 {
    let per_point: usize = POINT_DATA
        .iter()
        .map(|(_, ty, ncomp)| ncomp * if *ty == "Int32" { 4 } else { 8 })
        .sum::<usize>()
        + 24
        + 16;
    (n * per_point + 8 * (POINT_DATA.len() + 4) + 4096) as u64
}

/// Bytes gathered before they go to the writer.
const CHUNK: usize = 1 << 16;

/// Write one snapshot of the real particles at time `time` (s) to `path` (.vtp).
pub fn write_snapshot<const D: usize>(
    path: &Path,
    particles: &Particles<D>,
    time: f64,
) -> Result<()> {
    write_piece(path, particles, 0..particles.n_real, time)
}

/// Write the real particles `range` at time `time` (s) to `path` (.vtp): a whole snapshot, or
/// one rank's piece of a parallel one (see [`write_parallel_index`]).
pub fn write_piece<const D: usize>(
    path: &Path,
    particles: &Particles<D>,
    range: Range<usize>,
    time: f64,
) -> Result<()> {
    if range.end > particles.n_real || range.start > range.end {
        return Err(Error::Invalid(format!(
            "{}: particles {range:?} are not within the {} real particles",
            path.display(),
            particles.n_real
        )));
    }
    let (n, o) = (range.len(), range.start);
    let p = particles;

    let field = vec![float_array("TIME", 1, 1, move |_, b| {
        b.extend_from_slice(&time.to_le_bytes())
    })];
    let pd = point_data(p, range);
    let points = vec![float_array("Points", n, 3, move |i, b| {
        f64s(b, &p.position3(o + i))
    })];
    let verts = vec![
        Array {
            name: "connectivity",
            ty: Ty::Int64,
            ncomp: 1,
            len: n,
            fill: Box::new(|i, b| b.extend_from_slice(&(i as i64).to_le_bytes())),
        },
        Array {
            name: "offsets",
            ty: Ty::Int64,
            ncomp: 1,
            len: n,
            fill: Box::new(|i, b| b.extend_from_slice(&(i as i64 + 1).to_le_bytes())),
        },
    ];

    // XML header, with each array's offset into the appended block.
    let mut offset = 0u64;
    let mut next = |a: &Array| {
        let o = offset;
        offset += 8 + a.byte_count();
        o
    };
    let mut xml = String::with_capacity(4096);
    xml.push_str("<?xml version=\"1.0\"?>\n");
    xml.push_str(
        "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" \
         header_type=\"UInt64\">\n  <PolyData>\n    <FieldData>\n",
    );
    for a in &field {
        data_array_xml(&mut xml, "      ", a, next(a), true);
    }
    xml.push_str("    </FieldData>\n");
    xml.push_str(&format!(
        "    <Piece NumberOfPoints=\"{n}\" NumberOfVerts=\"{n}\" NumberOfLines=\"0\" \
         NumberOfStrips=\"0\" NumberOfPolys=\"0\">\n"
    ));
    xml.push_str("      <PointData Scalars=\"pressure\" Vectors=\"velocity\">\n");
    for a in &pd {
        data_array_xml(&mut xml, "        ", a, next(a), false);
    }
    xml.push_str("      </PointData>\n      <Points>\n");
    for a in &points {
        data_array_xml(&mut xml, "        ", a, next(a), false);
    }
    xml.push_str("      </Points>\n      <Verts>\n");
    for a in &verts {
        data_array_xml(&mut xml, "        ", a, next(a), false);
    }
    xml.push_str(
        "      </Verts>\n    </Piece>\n  </PolyData>\n  <AppendedData encoding=\"raw\">\n   _",
    );

    atomic::write_with(path, |tmp| {
        let file = File::create(tmp).map_err(|e| Error::io(path, e))?;
        write_appended(
            path,
            BufWriter::with_capacity(1 << 20, file),
            &xml,
            &[&field, &pd, &points, &verts],
        )
    })
}

/// The XML header, then each array's byte count and data, then the closing tags.
fn write_appended(
    path: &Path,
    mut w: BufWriter<File>,
    xml: &str,
    groups: &[&[Array]],
) -> Result<()> {
    let io = |e: std::io::Error| Error::io(path, e);
    w.write_all(xml.as_bytes()).map_err(io)?;
    let mut buf = Vec::with_capacity(CHUNK + 128);
    for a in groups.iter().flat_map(|g| g.iter()) {
        let count = a.byte_count();
        w.write_all(&count.to_le_bytes()).map_err(io)?;
        let mut written = 0u64;
        for i in 0..a.len {
            (a.fill)(i, &mut buf);
            if buf.len() >= CHUNK {
                written += buf.len() as u64;
                w.write_all(&buf).map_err(io)?;
                buf.clear();
            }
        }
        written += buf.len() as u64;
        w.write_all(&buf).map_err(io)?;
        buf.clear();
        if written != count {
            return Err(Error::Invalid(format!(
                "{}: array `{}` wrote {written} bytes, header says {count}",
                path.display(),
                a.name
            )));
        }
    }
    w.write_all(b"\n  </AppendedData>\n</VTKFile>\n")
        .map_err(io)?;
    w.flush().map_err(io)?;
    Ok(())
}

/// Escape text for an XML attribute value.
fn xml_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    out
}

/// Write the index of a parallel snapshot (.pvtp, VTK's PPolyData) at `path`, naming its
/// pieces `pieces` (.vtp files written by [`write_piece`], relative to the index's folder) in
/// order: ParaView reads them as one data set. The arrays are declared as [`POINT_DATA`] and
/// the points as `write_piece` writes them; the time is in each piece's FieldData.
pub fn write_parallel_index(path: &Path, pieces: &[String]) -> Result<()> {
    use std::fmt::Write as _;
    let mut xml = String::with_capacity(2048 + 64 * pieces.len());
    xml.push_str("<?xml version=\"1.0\"?>\n");
    xml.push_str(
        "<VTKFile type=\"PPolyData\" version=\"1.0\" byte_order=\"LittleEndian\" \
         header_type=\"UInt64\">\n  <PPolyData GhostLevel=\"0\">\n",
    );
    xml.push_str("    <PPointData Scalars=\"pressure\" Vectors=\"velocity\">\n");
    for (name, ty, ncomp) in POINT_DATA {
        let _ = write!(xml, "      <PDataArray type=\"{ty}\" Name=\"{name}\"");
        if ncomp != 1 {
            let _ = write!(xml, " NumberOfComponents=\"{ncomp}\"");
        }
        xml.push_str("/>\n");
    }
    xml.push_str("    </PPointData>\n    <PPoints>\n");
    xml.push_str("      <PDataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\"/>\n");
    xml.push_str("    </PPoints>\n");
    for piece in pieces {
        let _ = writeln!(xml, "    <Piece Source=\"{}\"/>", xml_escape(piece));
    }
    xml.push_str("  </PPolyData>\n</VTKFile>\n");
    atomic::write(path, xml.as_bytes())
}

/// A .pvd collection (ParaView time series) of snapshot files.
#[derive(Debug, Clone)]
pub struct PvdWriter {
    path: PathBuf,
    entries: Vec<(f64, String)>,
}

impl PvdWriter {
    /// A collection to be written at `path`; nothing is written until the first [`Self::add`].
    pub fn new(path: &Path) -> Self {
        PvdWriter {
            path: path.to_path_buf(),
            entries: Vec::new(),
        }
    }

    /// A collection that continues the listed snapshots (a resumed run).
    pub fn resume(path: &Path, entries: Vec<(f64, String)>) -> Self {
        PvdWriter {
            path: path.to_path_buf(),
            entries,
        }
    }

    /// The snapshots listed so far.
    pub fn entries(&self) -> &[(f64, String)] {
        &self.entries
    }

    /// The .pvd file path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Number of snapshots listed.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// List one snapshot (`file_name_relative`: relative to the .pvd's folder) at `time` (s)
    /// and rewrite the .pvd, through a temporary file and a rename, so that the file on disk is
    /// always a complete, valid collection even if the run dies later.
    pub fn add(&mut self, time: f64, file_name_relative: &str) -> Result<()> {
        self.entries.push((time, file_name_relative.to_string()));
        let mut xml = String::with_capacity(128 + 80 * self.entries.len());
        xml.push_str("<?xml version=\"1.0\"?>\n");
        xml.push_str(
            "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  \
             <Collection>\n",
        );
        for (t, file) in &self.entries {
            xml.push_str(&format!(
                "    <DataSet timestep=\"{t:e}\" group=\"\" part=\"0\" file=\"{}\"/>\n",
                xml_escape(file)
            ));
        }
        xml.push_str("  </Collection>\n</VTKFile>\n");

        atomic::write(&self.path, xml.as_bytes())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::particles::{Tensor, Vector};

    #[test]
    fn stress_2d_has_out_of_plane_component() {
        let mut p = Particles::<2>::default();
        p.push(Vector::<2>::zeros(), Vector::<2>::zeros(), 1.0, 1.0, 1.0, 0);
        p.s[0] = crate::tensor::Sym::from_full(&Tensor::<2>::new(1.0, 2.0, 2.0, 3.0));
        let s = deviatoric_stress3(&p, 0);
        assert_eq!(s, [1.0, 2.0, 0.0, 2.0, 3.0, 0.0, 0.0, 0.0, -4.0]);
    }

    #[test]
    fn point_data_table_matches_arrays() {
        let mut p = Particles::<3>::default();
        p.push(Vector::<3>::zeros(), Vector::<3>::zeros(), 1.0, 1.0, 1.0, 0);
        let arrays = point_data(&p, 0..1);
        assert_eq!(arrays.len(), POINT_DATA.len());
        for (a, (name, ty, ncomp)) in arrays.iter().zip(POINT_DATA) {
            assert_eq!((a.name, a.ty.name(), a.ncomp), (name, ty, ncomp));
            let mut b = Vec::new();
            (a.fill)(0, &mut b);
            assert_eq!(b.len() as u64, a.byte_count());
        }
    }

    #[test]
    fn escape_attribute() {
        assert_eq!(xml_escape("a&b<\"c\">"), "a&amp;b&lt;&quot;c&quot;&gt;");
    }
}
