//! VTK XML unstructured grid (`.vtu`) of the model's tets, with cell data
//! `region` (0 steel, 1 concrete, the codes of the solve's field files),
//! `quality` (3 r_in / R_circ) and `size`
//! (eq. 11, m). Binary data in one raw appended block (UInt64 headers),
//! which ParaView and meshio read.

use crate::build::tet_quality;
use crate::model::{Model, Region};

/// VTK cell type of a linear tetrahedron.
const VTK_TETRA: u8 = 10;

/// Encodes the model's tets as a `.vtu` document.
pub fn model_vtu(model: &Model) -> Vec<u8> {
    let mut arrays: Vec<(String, Vec<u8>)> = Vec::new();
    let mut push = |header: String, data: Vec<u8>| arrays.push((header, data));

    let points: Vec<u8> = model
        .nodes
        .iter()
        .flat_map(|p| p.iter().flat_map(|x| x.to_le_bytes()))
        .collect();
    push(
        r#"<DataArray type="Float64" NumberOfComponents="3" format="appended" offset="{}"/>"#
            .into(),
        points,
    );
    let conn: Vec<u8> = model
        .tets
        .iter()
        .flat_map(|t| t.iter().flat_map(|&i| (i as i64).to_le_bytes()))
        .collect();
    push(
        r#"<DataArray type="Int64" Name="connectivity" format="appended" offset="{}"/>"#.into(),
        conn,
    );
    let offsets: Vec<u8> = (1..=model.tets.len() as i64)
        .flat_map(|k| (4 * k).to_le_bytes())
        .collect();
    push(
        r#"<DataArray type="Int64" Name="offsets" format="appended" offset="{}"/>"#.into(),
        offsets,
    );
    push(
        r#"<DataArray type="UInt8" Name="types" format="appended" offset="{}"/>"#.into(),
        vec![VTK_TETRA; model.tets.len()],
    );
    let region: Vec<u8> = model
        .tet_region
        .iter()
        .flat_map(|r| {
            match r {
                Region::Steel => 0i32,
                Region::Concrete => 1i32,
            }
            .to_le_bytes()
        })
        .collect();
    push(
        r#"<DataArray type="Int32" Name="region" format="appended" offset="{}"/>"#.into(),
        region,
    );
    let quality: Vec<u8> = model
        .tets
        .iter()
        .flat_map(|t| tet_quality(t.map(|i| model.nodes[i as usize])).to_le_bytes())
        .collect();
    push(
        r#"<DataArray type="Float64" Name="quality" format="appended" offset="{}"/>"#.into(),
        quality,
    );
    let size: Vec<u8> = model
        .tet_size
        .iter()
        .flat_map(|s| s.to_le_bytes())
        .collect();
    push(
        r#"<DataArray type="Float64" Name="size" format="appended" offset="{}"/>"#.into(),
        size,
    );

    let mut offset = 0usize;
    let mut headers = Vec::new();
    for (h, data) in &arrays {
        headers.push(h.replace("{}", &offset.to_string()));
        offset += 8 + data.len();
    }
    let mut out = String::new();
    out.push_str("<?xml version=\"1.0\"?>\n");
    out.push_str("<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n");
    out.push_str("<UnstructuredGrid>\n");
    out.push_str(&format!(
        "<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n",
        model.nodes.len(),
        model.tets.len()
    ));
    out.push_str(&format!("<Points>\n{}\n</Points>\n", headers[0]));
    out.push_str(&format!(
        "<Cells>\n{}\n{}\n{}\n</Cells>\n",
        headers[1], headers[2], headers[3]
    ));
    out.push_str(&format!(
        "<CellData Scalars=\"region\">\n{}\n{}\n{}\n</CellData>\n",
        headers[4], headers[5], headers[6]
    ));
    out.push_str("</Piece>\n</UnstructuredGrid>\n<AppendedData encoding=\"raw\">\n_");
    let mut bytes = out.into_bytes();
    bytes.reserve(offset + 64);
    for (_, data) in &arrays {
        bytes.extend_from_slice(&(data.len() as u64).to_le_bytes());
        bytes.extend_from_slice(data);
    }
    bytes.extend_from_slice(b"\n</AppendedData>\n</VTKFile>\n");
    bytes
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The appended block holds every array at its declared offset with a
    /// UInt64 byte count matching the array's type and length (VTK XML format).
    #[test]
    fn appended_offsets_and_sizes_match() {
        let model = Model {
            nodes: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
                [0.0, 0.0, -1.0],
            ],
            node_region: vec![Region::Steel; 5],
            tets: vec![[0, 1, 2, 3], [0, 2, 1, 4]],
            tet_region: vec![Region::Steel, Region::Concrete],
            tet_size: vec![1.0, 1.0],
            ..Model::default()
        };
        let bytes = model_vtu(&model);
        let start = bytes.windows(2).position(|w| w == b"\n_").unwrap() + 2;
        let header = std::str::from_utf8(&bytes[..start]).unwrap();
        assert!(header.contains("NumberOfPoints=\"5\" NumberOfCells=\"2\""));
        // (name, element width, count) in declaration order.
        let expect = [
            ("Float64\" NumberOfComponents=\"3\"", 8, 15),
            ("Name=\"connectivity\"", 8, 8),
            ("Name=\"offsets\"", 8, 2),
            ("Name=\"types\"", 1, 2),
            ("Name=\"region\"", 4, 2),
            ("Name=\"quality\"", 8, 2),
            ("Name=\"size\"", 8, 2),
        ];
        let mut pos = start;
        for (name, width, count) in expect {
            let line = header.lines().find(|l| l.contains(name)).unwrap();
            let off: usize = line
                .split("offset=\"")
                .nth(1)
                .unwrap()
                .split('"')
                .next()
                .unwrap()
                .parse()
                .unwrap();
            assert_eq!(start + off, pos, "{name}");
            let n = u64::from_le_bytes(bytes[pos..pos + 8].try_into().unwrap()) as usize;
            assert_eq!(n, width * count, "{name}");
            pos += 8 + n;
        }
        assert_eq!(&bytes[pos..], b"\n</AppendedData>\n</VTKFile>\n");
        // The region array says steel (0) then concrete (1), as the field
        // files do; offsets end at 8.
        let region_at = bytes.len() - 28 - (8 + 16) - (8 + 16) - 8;
        assert_eq!(&bytes[region_at..region_at + 8], &[0, 0, 0, 0, 1, 0, 0, 0]);
    }
}
