//! A brick-sparse volume level: the MIP levels of a volume held as [`BRICK`]³ bricks of
//! RGBA8 colour (and snorm8 normals), only the bricks that hold a non-zero byte allocated,
//! and in them only the texels that do. `voxelize --prune` builds its levels in this form
//! and hands them to `emptyspace` ([`crate::emptyspace::prune_sparse`]), so the dense
//! volume is never materialised; a tier reads it through the empty-space removal's
//! `TierTexels` (`emptyspace::sparse_tier`) and comes out byte for byte as from the dense
//! levels (an absent brick reads as the zeros the dense level holds there). A neutral
//! module: the voxelizer writes it, the empty-space removal reads it, neither owns it.

/// Brick side in texels.
pub const BRICK: usize = 8;
const B3: usize = BRICK * BRICK * BRICK;
const EMPTY: u32 = u32::MAX;

/// Which texels of a brick are stored: bit `i % 64` of word `i / 64` for the texel at
/// index `i` inside the brick (x fastest).
pub type BrickMask = [u64; B3 / 64];

/// One MIP level, brick-sparse (see the module docs). Inside an allocated brick only the
/// texels with a non-zero byte are stored, packed in the brick's texel order (a mask per
/// brick says which): at 1024³ the bench tree's level 0 has 665,052 bricks holding
/// 63.1 M such texels (18.5 %), 0.55 GB packed with normals against 2.7 GB as whole bricks.
#[derive(Clone, Debug, PartialEq)]
pub struct SparseLevel {
    /// Level size in texels.
    pub dims: [usize; 3],
    /// Bricks per axis (`ceil(dims / BRICK)`).
    nb: [usize; 3],
    /// Per brick (x fastest), its slot or `EMPTY`.
    slot: Vec<u32>,
    /// Per slot, its brick.
    bricks: Vec<u32>,
    /// Per slot, its stored texels.
    mask: Vec<BrickMask>,
    /// Per slot, the index of its first stored texel in `colour` (and `normals`).
    first: Vec<usize>,
    /// The stored texels' colour bytes, slot after slot.
    colour: Vec<[u8; 4]>,
    normals: Option<Vec<[u8; 4]>>,
}

/// A texel's index inside its brick.
#[inline]
fn local(p: [usize; 3]) -> usize {
    (p[0] % BRICK) + BRICK * ((p[1] % BRICK) + BRICK * (p[2] % BRICK))
}

/// Stored texels of `m` before texel `i` (`i` itself not counted).
#[inline]
fn rank(m: &BrickMask, i: usize) -> usize {
    let (w, b) = (i / 64, i % 64);
    m[..w]
        .iter()
        .map(|x| x.count_ones() as usize)
        .sum::<usize>()
        + (m[w] & ((1u64 << b) - 1)).count_ones() as usize
}

impl SparseLevel {
    /// A level of `dims` whose slot `i` is brick `bricks[i]` (x-fastest brick index, all
    /// distinct), with `4 · BRICK³` bytes per slot of colour (and normals), x fastest
    /// inside the brick. Bytes of texels outside `dims` must be zero.
    pub fn from_bricks(
        dims: [usize; 3],
        bricks: Vec<u32>,
        colour: Vec<u8>,
        normals: Option<Vec<u8>>,
    ) -> SparseLevel {
        assert_eq!(
            colour.len(),
            bricks.len() * 4 * B3,
            "colour bytes per brick"
        );
        if let Some(n) = &normals {
            assert_eq!(n.len(), colour.len(), "normal bytes per brick");
        }
        let texel = |bytes: &[u8], i: usize| -> [u8; 4] {
            [
                bytes[4 * i],
                bytes[4 * i + 1],
                bytes[4 * i + 2],
                bytes[4 * i + 3],
            ]
        };
        let mut mask = vec![[0u64; B3 / 64]; bricks.len()];
        let (mut c, mut n) = (Vec::new(), normals.as_ref().map(|_| Vec::new()));
        for (s, m) in mask.iter_mut().enumerate() {
            for i in 0..B3 {
                let at = s * B3 + i;
                let t = texel(&colour, at);
                let tn = normals.as_deref().map_or([0; 4], |nb| texel(nb, at));
                if t != [0; 4] || tn != [0; 4] {
                    m[i / 64] |= 1 << (i % 64);
                    c.push(t);
                    if let Some(n) = n.as_mut() {
                        n.push(tn);
                    }
                }
            }
        }
        Self::from_packed(dims, bricks, mask, c, n)
    }

    /// A level of `dims` whose slot `i` is brick `bricks[i]` (all distinct), storing the
    /// texels of `mask[i]` ([`BrickMask`]); `colour` (and `normals`) hold the stored
    /// texels, slot after slot, in each brick's texel order. Stored texels must lie inside
    /// `dims`.
    pub fn from_packed(
        dims: [usize; 3],
        bricks: Vec<u32>,
        mask: Vec<BrickMask>,
        colour: Vec<[u8; 4]>,
        normals: Option<Vec<[u8; 4]>>,
    ) -> SparseLevel {
        let nb = dims.map(|d| d.div_ceil(BRICK));
        assert_eq!(mask.len(), bricks.len(), "one mask per brick");
        let mut slot = vec![EMPTY; nb.iter().product()];
        for (s, &b) in bricks.iter().enumerate() {
            assert_eq!(slot[b as usize], EMPTY, "brick {b} given twice");
            slot[b as usize] = s as u32;
        }
        let mut first = Vec::with_capacity(mask.len());
        let mut total = 0usize;
        for m in &mask {
            first.push(total);
            total += m.iter().map(|w| w.count_ones() as usize).sum::<usize>();
        }
        assert_eq!(colour.len(), total, "one colour per stored texel");
        if let Some(n) = &normals {
            assert_eq!(n.len(), total, "one normal per stored texel");
        }
        SparseLevel {
            dims,
            nb,
            slot,
            bricks,
            mask,
            first,
            colour,
            normals,
        }
    }

    pub fn has_normals(&self) -> bool {
        self.normals.is_some()
    }

    /// Bricks allocated.
    pub fn brick_count(&self) -> usize {
        self.bricks.len()
    }

    /// Texels stored.
    pub fn texel_count(&self) -> usize {
        self.colour.len()
    }

    /// Bytes held (the stored texels' colour and normals, the masks and the brick table).
    pub fn heap_bytes(&self) -> u64 {
        let per_slot = 4 + std::mem::size_of::<BrickMask>() + std::mem::size_of::<usize>();
        (4 * (self.colour.len() + self.normals.as_ref().map_or(0, Vec::len))
            + per_slot * self.bricks.len()
            + 4 * self.slot.len()) as u64
    }

    /// Bytes of the level stored densely (colour, and normals when present).
    pub fn dense_bytes(&self) -> u64 {
        let n: usize = self.dims.iter().product();
        (4 * n * (1 + self.has_normals() as usize)) as u64
    }

    /// Removes the normals.
    pub fn drop_normals(&mut self) {
        self.normals = None;
    }

    /// Whether every byte is zero.
    pub fn is_zero(&self) -> bool {
        self.colour.iter().all(|&b| b == [0; 4])
            && self
                .normals
                .as_ref()
                .is_none_or(|n| n.iter().all(|&b| b == [0; 4]))
    }

    #[inline]
    fn brick_coords(&self, b: usize) -> [usize; 3] {
        [
            b % self.nb[0],
            (b / self.nb[0]) % self.nb[1],
            b / (self.nb[0] * self.nb[1]),
        ]
    }

    /// Colour (or normal) bytes at `p` (inside `dims`); zero where no texel is stored.
    #[inline]
    pub fn get(&self, normals: bool, p: [usize; 3]) -> [u8; 4] {
        let bc = p.map(|v| v / BRICK);
        let s = self.slot[bc[0] + self.nb[0] * (bc[1] + self.nb[1] * bc[2])];
        if s == EMPTY {
            return [0; 4];
        }
        let bytes = if normals {
            match &self.normals {
                Some(n) => n,
                None => return [0; 4],
            }
        } else {
            &self.colour
        };
        let (m, i) = (&self.mask[s as usize], local(p));
        if m[i / 64] >> (i % 64) & 1 == 0 {
            return [0; 4];
        }
        bytes[self.first[s as usize] + rank(m, i)]
    }

    /// Calls `f(p, colour)` for every stored texel, brick after brick (in slot order),
    /// x fastest inside a brick; texels not stored are zero.
    pub fn for_each_texel(&self, f: &mut dyn FnMut([usize; 3], [u8; 4])) {
        self.for_each_stored(|p, k| f(p, self.colour[k]));
    }

    /// Calls `f(p, k)` for every stored texel in [`Self::for_each_texel`]'s order, `k`
    /// its index in `colour` (and `normals`).
    fn for_each_stored(&self, mut f: impl FnMut([usize; 3], usize)) {
        for (s, &b) in self.bricks.iter().enumerate() {
            let o = self.brick_coords(b as usize).map(|c| c * BRICK);
            let mut k = self.first[s];
            for (w, &word) in self.mask[s].iter().enumerate() {
                let mut bits = word;
                while bits != 0 {
                    let i = 64 * w + bits.trailing_zeros() as usize;
                    bits &= bits - 1;
                    let p = [
                        o[0] + i % BRICK,
                        o[1] + (i / BRICK) % BRICK,
                        o[2] + i / (BRICK * BRICK),
                    ];
                    f(p, k);
                    k += 1;
                }
            }
        }
    }

    /// The alpha (byte / 255) of every texel of brick `bc` into `out` (x fastest inside
    /// the brick, zero where nothing is stored); `false` (and `out` untouched) for a brick
    /// that is not allocated.
    pub(crate) fn brick_alpha(&self, bc: [usize; 3], out: &mut [f32; B3]) -> bool {
        let s = self.slot[bc[0] + self.nb[0] * (bc[1] + self.nb[1] * bc[2])];
        if s == EMPTY {
            return false;
        }
        out.fill(0.0);
        let mut k = self.first[s as usize];
        for (w, &word) in self.mask[s as usize].iter().enumerate() {
            let mut bits = word;
            while bits != 0 {
                let i = 64 * w + bits.trailing_zeros() as usize;
                bits &= bits - 1;
                out[i] = f32::from(self.colour[k][3]) / 255.0;
                k += 1;
            }
        }
        true
    }

    /// Replaces every stored texel's colour `c` by `f(c)`; `f` must keep a non-zero colour
    /// non-zero (what is stored does not change).
    pub(crate) fn map_colour(&mut self, f: impl Fn([u8; 4]) -> [u8; 4] + Sync) {
        use rayon::prelude::*;
        self.colour.par_iter_mut().for_each(|c| *c = f(*c));
    }

    /// Zeroes the colour and normal of every texel whose alpha byte is ≤ `threshold`
    /// ([`crate::emptyspace::occupancy::apply_threshold`]); 0 changes nothing.
    pub fn apply_threshold(&mut self, threshold: u8) {
        if threshold == 0 {
            return;
        }
        for (i, c) in self.colour.iter_mut().enumerate() {
            if c[3] <= threshold {
                *c = [0; 4];
                if let Some(n) = self.normals.as_mut() {
                    n[i] = [0; 4];
                }
            }
        }
    }

    /// The dense level: colour, and normals when present (x fastest, then y, then z).
    pub fn to_dense(&self) -> (Vec<u8>, Option<Vec<u8>>) {
        let n: usize = self.dims.iter().product();
        let d = self.dims;
        let scatter = |src: &[[u8; 4]]| {
            let mut out = vec![0u8; 4 * n];
            self.for_each_stored(|[x, y, z], k| {
                let at = 4 * (x + d[0] * (y + d[1] * z));
                out[at..at + 4].copy_from_slice(&src[k]);
            });
            out
        };
        (scatter(&self.colour), self.normals.as_deref().map(scatter))
    }
}

/// The levels of a dense volume (`levels[l]`: RGBA8 of `dims[l]`), brick-sparse: the
/// bricks with a non-zero colour or normal byte (tests, and a reference for producers).
pub fn from_dense(
    dims: &[[usize; 3]],
    levels: &[Vec<u8>],
    normals: Option<&[Vec<u8>]>,
) -> Vec<SparseLevel> {
    (0..levels.len())
        .map(|l| {
            let d = dims[l];
            let nb = d.map(|v| v.div_ceil(BRICK));
            let (mut bricks, mut colour) = (Vec::new(), Vec::new());
            let mut nrm = normals.map(|_| Vec::new());
            let mut c = vec![0u8; 4 * B3];
            let mut n = vec![0u8; 4 * B3];
            for bz in 0..nb[2] {
                for by in 0..nb[1] {
                    for bx in 0..nb[0] {
                        c.fill(0);
                        n.fill(0);
                        let mut any = false;
                        for z in bz * BRICK..((bz + 1) * BRICK).min(d[2]) {
                            for y in by * BRICK..((by + 1) * BRICK).min(d[1]) {
                                for x in bx * BRICK..((bx + 1) * BRICK).min(d[0]) {
                                    let o = 4 * (x + d[0] * (y + d[1] * z));
                                    let i = 4 * local([x, y, z]);
                                    c[i..i + 4].copy_from_slice(&levels[l][o..o + 4]);
                                    if let Some(nr) = normals {
                                        n[i..i + 4].copy_from_slice(&nr[l][o..o + 4]);
                                    }
                                    any |= c[i..i + 4] != [0; 4] || n[i..i + 4] != [0; 4];
                                }
                            }
                        }
                        if any {
                            bricks.push((bx + nb[0] * (by + nb[1] * bz)) as u32);
                            colour.extend_from_slice(&c);
                            if let Some(v) = nrm.as_mut() {
                                v.extend_from_slice(&n);
                            }
                        }
                    }
                }
            }
            SparseLevel::from_bricks(d, bricks, colour, nrm)
        })
        .collect()
}
