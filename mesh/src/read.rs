//! Reading gmsh `.msh` 4.1 files (ASCII or binary) into a [`RawMesh`].
//!
//! The data is decoded by `mshio`. Before that, a structural scan of the
//! file checks every count against the bytes that remain (a truncated or
//! corrupt file must give an error, not a huge allocation or a panic),
//! reads `$PhysicalNames` (which mshio skips) and reads the node tags
//! (which mshio drops when they are dense: the file order of nodes is not
//! guaranteed to be the tag order, so every tag is mapped explicitly).

use crate::MeshError;
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

/// A mesh as read from a `.msh`: nodes in file order, and the linear tets
/// and triangles of every named physical group, by node index.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RawMesh {
    /// The file read (named in later errors).
    pub source: PathBuf,
    /// Node coordinates, m, indexed 0.. in file order.
    pub nodes: Vec<[f64; 3]>,
    /// gmsh's tag of each node.
    pub node_tags: Vec<u64>,
    /// Tets (gmsh node order) of each physical volume, by name.
    pub volumes: BTreeMap<String, Vec<[u32; 4]>>,
    /// Triangles (gmsh node order) of each physical surface, by name.
    pub surfaces: BTreeMap<String, Vec<[u32; 3]>>,
}

/// What the structural scan learns: names of physical groups and node tags per block.
struct Scan {
    physical_names: HashMap<(i32, i32), String>,
    node_block_tags: Vec<Vec<u64>>,
}

struct Cursor<'a> {
    data: &'a [u8],
    pos: usize,
    binary: bool,
    size_t: usize,
}

type ScanResult<T> = Result<T, String>;

impl<'a> Cursor<'a> {
    fn remaining(&self) -> usize {
        self.data.len() - self.pos
    }
    fn skip_ws(&mut self) {
        while self.pos < self.data.len() && self.data[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
    }
    fn token(&mut self, what: &str) -> ScanResult<&'a str> {
        self.skip_ws();
        let start = self.pos;
        while self.pos < self.data.len() && !self.data[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        if start == self.pos {
            return Err(format!(
                "file ends where {what} was expected (byte {start})"
            ));
        }
        std::str::from_utf8(&self.data[start..self.pos])
            .map_err(|_| format!("non-text bytes where {what} was expected (byte {start})"))
    }
    fn bytes(&mut self, n: usize, what: &str) -> ScanResult<&'a [u8]> {
        if self.remaining() < n {
            return Err(format!(
                "file ends inside {what} (byte {}, {} bytes needed, {} left)",
                self.pos,
                n,
                self.remaining()
            ));
        }
        let b = &self.data[self.pos..self.pos + n];
        self.pos += n;
        Ok(b)
    }
    fn size(&mut self, what: &str) -> ScanResult<u64> {
        if self.binary {
            let b = self.bytes(self.size_t, what)?;
            Ok(match self.size_t {
                8 => u64::from_le_bytes(b.try_into().expect("8 bytes")),
                _ => u32::from_le_bytes(b.try_into().expect("4 bytes")) as u64,
            })
        } else {
            let t = self.token(what)?;
            t.parse().map_err(|_| {
                format!(
                    "{what}: {t:?} is not an unsigned integer (byte {})",
                    self.pos
                )
            })
        }
    }
    fn int(&mut self, what: &str) -> ScanResult<i32> {
        if self.binary {
            let b = self.bytes(4, what)?;
            Ok(i32::from_le_bytes(b.try_into().expect("4 bytes")))
        } else {
            let t = self.token(what)?;
            t.parse()
                .map_err(|_| format!("{what}: {t:?} is not an integer (byte {})", self.pos))
        }
    }
    /// Skips `n` values of `width` bytes (binary) or `n` tokens (ASCII).
    fn skip_values(&mut self, n: u64, width: usize, what: &str) -> ScanResult<()> {
        if self.binary {
            let bytes = (n as u128) * (width as u128);
            if bytes > self.remaining() as u128 {
                return Err(format!(
                    "file ends inside {what} (byte {}, {} values announced, {} bytes left)",
                    self.pos,
                    n,
                    self.remaining()
                ));
            }
            self.pos += bytes as usize;
        } else {
            self.check_count(n, what)?;
            for _ in 0..n {
                self.token(what)?;
            }
        }
        Ok(())
    }
    /// Rejects a count larger than the bytes left could hold (each value takes ≥ 1 byte).
    fn check_count(&self, n: u64, what: &str) -> ScanResult<()> {
        if n > self.remaining() as u64 {
            return Err(format!(
                "{what}: count {n} exceeds what the remaining {} bytes can hold (byte {})",
                self.remaining(),
                self.pos
            ));
        }
        Ok(())
    }
    fn expect_line(&mut self, tag: &str) -> ScanResult<()> {
        self.skip_ws();
        let start = self.pos;
        let t = self.token(tag)?;
        if t != tag {
            return Err(format!("expected {tag} at byte {start}, found {t:?}"));
        }
        Ok(())
    }
}

fn scan(data: &[u8]) -> ScanResult<Scan> {
    let mut c = Cursor {
        data,
        pos: 0,
        binary: false,
        size_t: 8,
    };
    let file_type = c.header()?;
    let mut out = Scan {
        physical_names: HashMap::new(),
        node_block_tags: Vec::new(),
    };
    let mut seen_nodes = false;
    let mut seen_elements = false;
    loop {
        c.skip_ws();
        if c.remaining() == 0 {
            break;
        }
        let start = c.pos;
        let section = c.token("a section header")?;
        if !section.starts_with('$') {
            return Err(format!(
                "expected a $Section header at byte {start}, found {section:?}"
            ));
        }
        let name = section[1..].to_string();
        // Section contents are binary in binary files except $PhysicalNames.
        c.binary = file_type == 1 && name != "PhysicalNames";
        if c.binary {
            c.bytes(1, "section header newline")?;
        }
        match name.as_str() {
            "PhysicalNames" => c.physical_names(&mut out)?,
            "Entities" => c.entities()?,
            "Nodes" => {
                if seen_nodes {
                    return Err("more than one $Nodes section".into());
                }
                seen_nodes = true;
                c.nodes(&mut out)?;
            }
            "Elements" => {
                if seen_elements {
                    return Err("more than one $Elements section".into());
                }
                seen_elements = true;
                c.elements()?;
            }
            _ => c.skip_section(&name)?,
        }
        c.binary = false;
        c.expect_line(&format!("$End{name}"))?;
    }
    if !seen_nodes {
        return Err("no $Nodes section".into());
    }
    if !seen_elements {
        return Err("no $Elements section".into());
    }
    Ok(out)
}

impl Cursor<'_> {
    /// `$MeshFormat`: version 4.1, ASCII or little-endian binary; returns
    /// the file type (0 ASCII, 1 binary) and sets the size_t width.
    fn header(&mut self) -> ScanResult<i32> {
        self.expect_line("$MeshFormat")?;
        let version = self.token("format version")?;
        if version != "4.1" {
            return Err(format!("format version {version} (only 4.1 is read)"));
        }
        let file_type = self.int("file type")?;
        let size_t: usize = self.int("data size")? as usize;
        if size_t != 4 && size_t != 8 {
            return Err(format!("unsupported size_t width {size_t}"));
        }
        self.size_t = size_t;
        if file_type == 1 {
            // A newline, then the integer 1 written in the file's byte order.
            self.bytes(1, "header")?;
            let one = self.bytes(4, "endianness marker")?;
            if i32::from_le_bytes(one.try_into().expect("4 bytes")) != 1 {
                return Err("big-endian binary files are not supported".into());
            }
        } else if file_type != 0 {
            return Err(format!(
                "file type {file_type} is neither ASCII (0) nor binary (1)"
            ));
        }
        self.expect_line("$EndMeshFormat")?;
        Ok(file_type)
    }

    fn physical_names(&mut self, out: &mut Scan) -> ScanResult<()> {
        let n = self.size("number of physical names")?;
        self.check_count(n, "number of physical names")?;
        for _ in 0..n {
            let dim = self.int("physical group dimension")?;
            let tag = self.int("physical group tag")?;
            self.skip_ws();
            let rest = &self.data[self.pos..];
            let end = rest
                .iter()
                .position(|&b| b == b'\n')
                .ok_or("file ends inside $PhysicalNames")?;
            let name = String::from_utf8_lossy(&rest[..end])
                .trim()
                .trim_matches('"')
                .to_string();
            self.pos += end;
            out.physical_names.insert((dim, tag), name);
        }
        Ok(())
    }

    /// `$Entities` is only checked and skipped.
    fn entities(&mut self) -> ScanResult<()> {
        let np = self.size("number of points")?;
        let nc = self.size("number of curves")?;
        let ns = self.size("number of surfaces")?;
        let nv = self.size("number of volumes")?;
        self.check_count(np + nc + ns + nv, "number of entities")?;
        for _ in 0..np {
            self.int("point tag")?;
            self.skip_values(3, 8, "point coordinates")?;
            let k = self.size("number of physical tags")?;
            self.skip_values(k, 4, "physical tags")?;
        }
        for what in [nc, ns, nv] {
            for _ in 0..what {
                self.int("entity tag")?;
                self.skip_values(6, 8, "entity bounding box")?;
                let k = self.size("number of physical tags")?;
                self.skip_values(k, 4, "physical tags")?;
                let k = self.size("number of bounding entities")?;
                self.skip_values(k, 4, "bounding entity tags")?;
            }
        }
        Ok(())
    }

    /// `$Nodes`: the node tags of each block (coordinates are skipped).
    fn nodes(&mut self, out: &mut Scan) -> ScanResult<()> {
        let blocks = self.size("number of node blocks")?;
        let total = self.size("number of nodes")?;
        self.size("min node tag")?;
        self.size("max node tag")?;
        self.check_count(blocks, "number of node blocks")?;
        self.check_count(total, "number of nodes")?;
        let mut count = 0u64;
        for b in 0..blocks {
            self.int("node block dimension")?;
            self.int("node block entity tag")?;
            if self.int("node block parametric flag")? != 0 {
                return Err(format!(
                    "node block {} has parametric coordinates (not read)",
                    b + 1
                ));
            }
            let n = self.size("number of nodes in block")?;
            self.check_count(n, "number of nodes in block")?;
            let mut tags = Vec::with_capacity(n as usize);
            for _ in 0..n {
                tags.push(self.size("node tag")?);
            }
            self.skip_values(3 * n, 8, "node coordinates")?;
            count += n;
            out.node_block_tags.push(tags);
        }
        if count != total {
            return Err(format!(
                "$Nodes announces {total} nodes, its blocks hold {count}"
            ));
        }
        Ok(())
    }

    /// `$Elements`: only the element types and counts are checked.
    fn elements(&mut self) -> ScanResult<()> {
        let blocks = self.size("number of element blocks")?;
        self.size("number of elements")?;
        self.size("min element tag")?;
        self.size("max element tag")?;
        self.check_count(blocks, "number of element blocks")?;
        for b in 0..blocks {
            self.int("element block dimension")?;
            self.int("element block entity tag")?;
            let ty = self.int("element type")?;
            let n = self.size("number of elements in block")?;
            let per = nodes_per_element(ty)
                .ok_or_else(|| format!("element block {}: element type {ty} is not read", b + 1))?;
            self.skip_values(n.saturating_mul(1 + per), self.size_t, "elements")?;
        }
        Ok(())
    }

    /// Skips an unknown section by its end marker.
    fn skip_section(&mut self, name: &str) -> ScanResult<()> {
        let end = format!("$End{name}");
        let rest = &self.data[self.pos..];
        let off = rest
            .windows(end.len())
            .position(|w| w == end.as_bytes())
            .ok_or_else(|| format!("file ends inside ${name}"))?;
        self.pos += off;
        Ok(())
    }
}

/// Nodes per element for the gmsh element types a specimen mesh can hold.
fn nodes_per_element(ty: i32) -> Option<u64> {
    Some(match ty {
        15 => 1,
        1 => 2,
        2 => 3,
        3 => 4,
        4 => 4,
        5 => 8,
        6 => 6,
        7 => 5,
        8 => 3,
        9 => 6,
        10 => 9,
        11 => 10,
        16 => 8,
        17 => 20,
        _ => return None,
    })
}

fn corrupt(path: &Path, detail: impl Into<String>) -> MeshError {
    MeshError::MshCorrupt {
        path: path.to_path_buf(),
        detail: detail.into(),
    }
}

/// Reads a gmsh `.msh` 4.1 file: nodes, and the tets and triangles of every
/// named physical group. Node tags are validated and mapped to indices.
pub fn read_msh(path: &Path) -> Result<RawMesh, MeshError> {
    let data = std::fs::read(path).map_err(|e| MeshError::io(path, e))?;
    parse_msh(&data, path)
}

/// [`read_msh`] on bytes already in memory; `path` is used in messages.
pub fn parse_msh(data: &[u8], path: &Path) -> Result<RawMesh, MeshError> {
    let scan = scan(data).map_err(|d| corrupt(path, d))?;
    // The scan bounded every count; a panic left in the parser is still
    // turned into an error rather than a crash.
    let parsed = std::panic::catch_unwind(|| {
        mshio::parse_msh_bytes(data).map_err(|e| {
            let offset = e
                .begin_msh_errors()
                .next()
                .map(|(rest, _)| data.len() - rest.len());
            let msgs: Vec<String> = e.filter_msh_errors().map(|(_, k)| k.to_string()).collect();
            format!("{} (byte {:?})", msgs.join("; "), offset)
        })
    })
    .map_err(|_| corrupt(path, "the .msh parser failed on malformed data"))?
    .map_err(|d| corrupt(path, d))?;

    let nodes_sec = parsed
        .data
        .nodes
        .as_ref()
        .ok_or_else(|| corrupt(path, "no $Nodes section"))?;
    if nodes_sec.node_blocks.len() != scan.node_block_tags.len() {
        return Err(corrupt(path, "node blocks differ between scans"));
    }
    let mut nodes = Vec::new();
    let mut node_tags = Vec::new();
    for (block, tags) in nodes_sec.node_blocks.iter().zip(&scan.node_block_tags) {
        if block.nodes.len() != tags.len() {
            return Err(corrupt(path, "node block sizes differ between scans"));
        }
        for (nd, &tag) in block.nodes.iter().zip(tags) {
            nodes.push([nd.x, nd.y, nd.z]);
            node_tags.push(tag);
        }
    }
    if nodes.len() >= u32::MAX as usize {
        return Err(corrupt(path, "too many nodes for 32-bit indices"));
    }
    let index = TagIndex::new(&node_tags)
        .map_err(|tag| corrupt(path, format!("node tag {tag} is defined twice")))?;

    // Entity (dim, tag) → physical group names.
    let mut entity_groups: HashMap<(i32, i32), Vec<String>> = HashMap::new();
    if let Some(ent) = &parsed.data.entities {
        let mut add = |dim: i32, tag: i32, phys: &[i32]| {
            for p in phys {
                // gmsh writes negative physical tags for reversed orientation.
                if let Some(name) = scan.physical_names.get(&(dim, p.abs())) {
                    entity_groups
                        .entry((dim, tag))
                        .or_default()
                        .push(name.clone());
                }
            }
        };
        for s in &ent.surfaces {
            add(2, s.tag, &s.physical_tags);
        }
        for v in &ent.volumes {
            add(3, v.tag, &v.physical_tags);
        }
    }

    let mut raw = RawMesh {
        source: path.to_path_buf(),
        nodes,
        node_tags,
        ..Default::default()
    };
    let elements = parsed
        .data
        .elements
        .as_ref()
        .ok_or_else(|| corrupt(path, "no $Elements section"))?;
    for block in &elements.element_blocks {
        let Some(groups) = entity_groups.get(&(block.entity_dim, block.entity_tag)) else {
            continue;
        };
        let ty = block.element_type as i32;
        for group in groups {
            match (block.entity_dim, ty) {
                (3, 4) => {
                    let v = raw.volumes.entry(group.clone()).or_default();
                    for e in &block.elements {
                        v.push(map_nodes::<4>(&index, e, path, group)?);
                    }
                }
                (2, 2) => {
                    let v = raw.surfaces.entry(group.clone()).or_default();
                    for e in &block.elements {
                        v.push(map_nodes::<3>(&index, e, path, group)?);
                    }
                }
                (3, _) | (2, _) => {
                    return Err(MeshError::Topology {
                        path: path.to_path_buf(),
                        detail: format!(
                            "physical group \"{group}\" holds elements of gmsh type {ty}; only linear tets (4) and triangles (2) are used"
                        ),
                    })
                }
                _ => {}
            }
        }
    }
    Ok(raw)
}

fn map_nodes<const N: usize>(
    index: &TagIndex,
    e: &mshio::Element<u64>,
    path: &Path,
    group: &str,
) -> Result<[u32; N], MeshError> {
    if e.nodes.len() != N {
        return Err(corrupt(
            path,
            format!(
                "element {} has {} nodes, expected {N}",
                e.element_tag,
                e.nodes.len()
            ),
        ));
    }
    let mut out = [0u32; N];
    for (o, &tag) in out.iter_mut().zip(&e.nodes) {
        *o = index.get(tag).ok_or_else(|| MeshError::BadNodeRef {
            path: path.to_path_buf(),
            group: group.to_string(),
            element: e.element_tag,
            tag,
        })?;
    }
    Ok(out)
}

/// gmsh node tag → node index.
enum TagIndex {
    Dense(Vec<u32>),
    Sparse(HashMap<u64, u32>),
}

impl TagIndex {
    fn new(tags: &[u64]) -> Result<TagIndex, u64> {
        let max = tags.iter().copied().max().unwrap_or(0);
        if max <= 4 * tags.len() as u64 + 1024 {
            let mut v = vec![u32::MAX; max as usize + 1];
            for (i, &t) in tags.iter().enumerate() {
                if v[t as usize] != u32::MAX {
                    return Err(t);
                }
                v[t as usize] = i as u32;
            }
            Ok(TagIndex::Dense(v))
        } else {
            let mut m = HashMap::with_capacity(tags.len());
            for (i, &t) in tags.iter().enumerate() {
                if m.insert(t, i as u32).is_some() {
                    return Err(t);
                }
            }
            Ok(TagIndex::Sparse(m))
        }
    }
    fn get(&self, tag: u64) -> Option<u32> {
        match self {
            TagIndex::Dense(v) => v.get(tag as usize).copied().filter(|&i| i != u32::MAX),
            TagIndex::Sparse(m) => m.get(&tag).copied(),
        }
    }
}
