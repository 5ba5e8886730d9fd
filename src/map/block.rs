//! A block of the TSDF: 8^3 voxels, either as integration writes them (16 bytes each, the whole
//! block) or packed, once no frame has touched it for a while: most of a block is unobserved
//! space behind a surface or free space in front of it, and a packed block keeps only what tells
//! its voxels apart. Packing is lossless: a packed block reads back voxel for voxel, bit for bit,
//! so what the map yields never depends on which blocks are packed.

use glam::IVec3;

use super::voxel::{SegmentLabel, Voxel};

/// Voxels along one side of a block.
pub const BLOCK_SIDE: usize = 8;
pub const BLOCK_VOXELS: usize = BLOCK_SIDE * BLOCK_SIDE * BLOCK_SIDE;
const WORDS: usize = BLOCK_VOXELS / 64;

#[derive(Clone)]
pub struct Block {
    pub key: IVec3,
    voxels: Voxels,
}

#[derive(Clone)]
enum Voxels {
    Whole(Box<[Voxel; BLOCK_VOXELS]>),
    Packed(Box<PackedVoxels>),
}

/// A block's voxels in three kinds: never observed (`Voxel::default()`, not stored), free space
/// (observed, the distance at the truncation, no colour and no label: only the weight stored)
/// and the rest, stored whole. Each kind's voxels are kept in slot order, and a slot's place in
/// its list is the count of the kind's bits before it: `rank` holds that count at the start of
/// each 64-slot word, so a lookup counts the bits of one word.
#[derive(Clone)]
struct PackedVoxels {
    /// Bit `i`: voxel `i` is free space.
    free: [u64; WORDS],
    /// Bit `i`: voxel `i` is stored whole.
    whole: [u64; WORDS],
    free_rank: [u16; WORDS],
    whole_rank: [u16; WORDS],
    /// The free voxels' distance (the map's truncation).
    free_sdf: f32,
    /// The free voxels' weights in fixed-point steps.
    free_weights: Box<[u16]>,
    whole_voxels: Box<[Voxel]>,
}

impl Block {
    pub fn new(key: IVec3) -> Self {
        Self {
            key,
            voxels: Voxels::Whole(Box::new([Voxel::default(); BLOCK_VOXELS])),
        }
    }

    /// The voxel at slot `index` (see [`voxel_index`]).
    pub fn voxel(&self, index: usize) -> Voxel {
        match &self.voxels {
            Voxels::Whole(voxels) => voxels[index],
            Voxels::Packed(packed) => packed.voxel(index),
        }
    }

    /// The block's voxels in slot order.
    pub fn voxels(&self) -> impl Iterator<Item = Voxel> + '_ {
        (0..BLOCK_VOXELS).map(|i| self.voxel(i))
    }

    /// The voxels to write, unpacking the block first when it is packed.
    pub fn voxels_mut(&mut self) -> &mut [Voxel; BLOCK_VOXELS] {
        if let Voxels::Packed(packed) = &self.voxels {
            self.voxels = Voxels::Whole(Box::new(std::array::from_fn(|i| packed.voxel(i))));
        }
        match &mut self.voxels {
            Voxels::Whole(voxels) => voxels,
            Voxels::Packed(_) => unreachable!("unpacked above"),
        }
    }

    /// Replaces labels as [`super::TsdfMap::relabel`] does.
    pub fn relabel(&mut self, relabel: &[SegmentLabel]) {
        let rename = |voxel: &mut Voxel| {
            if let Some(&l) = relabel.get(voxel.label as usize) {
                voxel.label = l;
            }
        };
        match &mut self.voxels {
            // Only voxels stored whole have a label other than 0, unless 0 itself is renamed.
            Voxels::Packed(packed) if relabel.first().is_none_or(|&l| l == 0) => {
                packed.whole_voxels.iter_mut().for_each(rename);
            }
            _ => self.voxels_mut().iter_mut().for_each(rename),
        }
    }

    pub fn is_packed(&self) -> bool {
        matches!(self.voxels, Voxels::Packed(_))
    }

    /// Packs the block; `free_sdf` is the distance free space is clamped to (the truncation).
    pub fn pack(&mut self, free_sdf: f32) {
        if let Voxels::Whole(voxels) = &self.voxels {
            self.voxels = Voxels::Packed(Box::new(PackedVoxels::new(voxels, free_sdf)));
        }
    }

    /// Bytes the block holds on the heap and in place.
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of::<Self>()
            + match &self.voxels {
                Voxels::Whole(_) => BLOCK_VOXELS * std::mem::size_of::<Voxel>(),
                Voxels::Packed(packed) => {
                    std::mem::size_of::<PackedVoxels>()
                        + packed.free_weights.len() * 2
                        + packed.whole_voxels.len() * std::mem::size_of::<Voxel>()
                }
            }
    }
}

impl PackedVoxels {
    fn new(voxels: &[Voxel; BLOCK_VOXELS], free_sdf: f32) -> Self {
        let mut packed = Self {
            free: [0; WORDS],
            whole: [0; WORDS],
            free_rank: [0; WORDS],
            whole_rank: [0; WORDS],
            free_sdf,
            free_weights: Box::new([]),
            whole_voxels: Box::new([]),
        };
        let (mut free_weights, mut whole_voxels) = (Vec::new(), Vec::new());
        for (i, v) in voxels.iter().enumerate() {
            let bit = 1u64 << (i % 64);
            if i % 64 == 0 {
                packed.free_rank[i / 64] = free_weights.len() as u16;
                packed.whole_rank[i / 64] = whole_voxels.len() as u16;
            }
            if bitwise_equal(v, &Voxel::default()) {
                continue;
            }
            let free = Voxel::free(free_sdf, v.weight);
            if v.weight > 0 && bitwise_equal(v, &free) {
                packed.free[i / 64] |= bit;
                free_weights.push(v.weight);
            } else {
                packed.whole[i / 64] |= bit;
                whole_voxels.push(*v);
            }
        }
        packed.free_weights = free_weights.into_boxed_slice();
        packed.whole_voxels = whole_voxels.into_boxed_slice();
        packed
    }

    fn voxel(&self, index: usize) -> Voxel {
        let (word, bit) = (index / 64, 1u64 << (index % 64));
        let before = bit - 1;
        if self.whole[word] & bit != 0 {
            let rank = usize::from(self.whole_rank[word])
                + (self.whole[word] & before).count_ones() as usize;
            self.whole_voxels[rank]
        } else if self.free[word] & bit != 0 {
            let rank = usize::from(self.free_rank[word])
                + (self.free[word] & before).count_ones() as usize;
            Voxel::free(self.free_sdf, self.free_weights[rank])
        } else {
            Voxel::default()
        }
    }
}

/// Equal bit for bit (a distance of -0.0 is not 0.0 here: packing keeps every bit).
fn bitwise_equal(a: &Voxel, b: &Voxel) -> bool {
    a.sdf.to_bits() == b.sdf.to_bits()
        && a.weight == b.weight
        && a.label_weight == b.label_weight
        && a.label == b.label
        && a.color == b.color
}

/// Index of voxel `local` (each coordinate in `0..BLOCK_SIDE`) inside its block.
pub fn voxel_index(local: IVec3) -> usize {
    local.x as usize + BLOCK_SIDE * (local.y as usize + BLOCK_SIDE * local.z as usize)
}

/// Local coordinates of the voxel at slot `index` of its block (the inverse of `voxel_index`).
pub fn voxel_local(index: usize) -> IVec3 {
    IVec3::new(
        (index % BLOCK_SIDE) as i32,
        ((index / BLOCK_SIDE) % BLOCK_SIDE) as i32,
        (index / (BLOCK_SIDE * BLOCK_SIDE)) as i32,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn arbitrary_voxel() -> impl Strategy<Value = Voxel> {
        // Mostly the three kinds packing tells apart, and some of everything else.
        prop_oneof![
            Just(Voxel::default()),
            (1u16..u16::MAX).prop_map(|w| Voxel::free(0.08, w)),
            (-0.08f32..0.08, 0.0f32..1000.0, any::<[u8; 3]>(), 0u32..20,)
                .prop_map(|(sdf, w, color, label)| Voxel::observed(sdf, w, color, label)),
            Just(Voxel::observed(-0.0, 1.0, [0; 3], 0)),
            Just(Voxel::observed(0.08, 1.0, [0, 0, 1], 0)),
        ]
    }

    proptest! {
        #[test]
        fn a_packed_block_reads_back_bit_for_bit(
            voxels in proptest::collection::vec(arbitrary_voxel(), BLOCK_VOXELS)
        ) {
            let mut block = Block::new(IVec3::new(1, -2, 3));
            block.voxels_mut().copy_from_slice(&voxels);
            block.pack(0.08);
            prop_assert!(block.is_packed());
            for (i, v) in voxels.iter().enumerate() {
                prop_assert!(bitwise_equal(&block.voxel(i), v), "slot {i}");
            }
            // Writing unpacks it, whole.
            block.voxels_mut()[7] = Voxel::observed(0.01, 2.0, [9; 3], 4);
            prop_assert!(!block.is_packed());
            prop_assert_eq!(block.voxel(7).label, 4);
            for (i, v) in voxels.iter().enumerate().filter(|(i, _)| *i != 7) {
                prop_assert!(bitwise_equal(&block.voxel(i), v), "slot {i}");
            }
        }
    }

    #[test]
    fn free_space_and_unobserved_space_take_a_fraction_of_a_whole_block() {
        let mut block = Block::new(IVec3::ZERO);
        let whole_bytes = block.memory_bytes();
        // A surface through the middle: free space in front, two layers of surface, nothing
        // behind.
        for (i, v) in block.voxels_mut().iter_mut().enumerate() {
            let z = voxel_local(i).z;
            *v = match z {
                0..=3 => Voxel::free(0.08, 640),
                4..=5 => Voxel::observed(0.02 * (3.5 - z as f32), 10.0, [200, 10, 10], 3),
                _ => Voxel::default(),
            };
        }
        block.pack(0.08);
        let packed_bytes = block.memory_bytes();
        assert!(
            packed_bytes * 2 < whole_bytes,
            "{packed_bytes} packed against {whole_bytes} whole"
        );
    }
}
