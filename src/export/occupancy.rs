//! The 2D occupancy layer in the ROS map_server format (PGM + YAML).
//!
//! Two grids over the same cells: the map layer, where a cell is occupied when the panoptic map
//! has surface in the robot's height band over it, free when the floor was seen there and nothing
//! stands in the band, unknown otherwise; and the object-projected cost map of Sivananda et al.,
//! which adds every object's complete model (points with z in [0.1 m, robot height]) projected
//! onto the floor, so a table whose top the robot would hit is an obstacle, not four legs.

use glam::{Vec2, Vec3};

use crate::geometry::TriMesh;

/// Cell size, metres.
pub const RESOLUTION_M: f32 = 0.05;
/// The height band a mobile base and its arm sweep (metres above the floor).
pub const ROBOT_BAND_M: (f32, f32) = (0.05, 1.5);
/// Object points below this height do not block a base (Sivananda et al.).
pub const OBJECT_MIN_Z_M: f32 = 0.1;
/// Map points below this height are floor.
const FLOOR_MAX_Z_M: f32 = 0.03;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cell {
    Unknown,
    Free,
    Occupied,
}

/// A grid of `width` x `height` cells; cell (0, 0) is the one at `origin` (its lower-left corner).
#[derive(Clone, Debug, PartialEq)]
pub struct OccupancyGrid {
    pub origin: Vec2,
    pub resolution: f32,
    pub width: usize,
    pub height: usize,
    /// Row-major from the bottom row (smallest y) up.
    pub cells: Vec<Cell>,
}

impl OccupancyGrid {
    /// An unknown grid covering `lo..hi` with a one-cell margin.
    fn covering(lo: Vec2, hi: Vec2, resolution: f32) -> Self {
        let origin = lo - Vec2::splat(resolution);
        let width = (((hi.x - origin.x) / resolution).ceil() as usize + 1).max(1);
        let height = (((hi.y - origin.y) / resolution).ceil() as usize + 1).max(1);
        Self {
            origin,
            resolution,
            width,
            height,
            cells: vec![Cell::Unknown; width * height],
        }
    }

    /// The index of the cell under `p`, if inside.
    pub fn index(&self, p: Vec2) -> Option<usize> {
        let c = ((p - self.origin) / self.resolution).floor();
        (c.x >= 0.0 && c.y >= 0.0 && (c.x as usize) < self.width && (c.y as usize) < self.height)
            .then(|| c.y as usize * self.width + c.x as usize)
    }

    pub fn count(&self, cell: Cell) -> usize {
        self.cells.iter().filter(|c| **c == cell).count()
    }

    /// The map layer from surface points of the aligned map (z up, floor at 0).
    pub fn from_map(points: &[Vec3]) -> Option<Self> {
        let first = points.first()?.truncate();
        let (lo, hi) = points.iter().fold((first, first), |(lo, hi), p| {
            (lo.min(p.truncate()), hi.max(p.truncate()))
        });
        let mut grid = Self::covering(lo, hi, RESOLUTION_M);
        // Floor first, obstacles over it.
        for p in points.iter().filter(|p| p.z.abs() <= FLOOR_MAX_Z_M) {
            if let Some(i) = grid.index(p.truncate()) {
                grid.cells[i] = Cell::Free;
            }
        }
        for p in points
            .iter()
            .filter(|p| p.z >= ROBOT_BAND_M.0 && p.z <= ROBOT_BAND_M.1)
        {
            if let Some(i) = grid.index(p.truncate()) {
                grid.cells[i] = Cell::Occupied;
            }
        }
        Some(grid)
    }

    /// The object-projected cost map: this grid with every part of `object_meshes` (world frame)
    /// between `OBJECT_MIN_Z_M` and the robot's height marked occupied.
    pub fn with_objects(&self, object_meshes: &[TriMesh]) -> Self {
        let mut grid = self.clone();
        let step = 0.5 * self.resolution;
        for mesh in object_meshes {
            for t in 0..mesh.triangles.len() {
                let [a, b, c] = mesh.triangle(t);
                let longest = (b - a).length().max((c - b).length()).max((a - c).length());
                let n = (longest / step).ceil().max(1.0) as usize;
                for i in 0..=n {
                    for j in 0..=(n - i) {
                        let (u, v) = (i as f32 / n as f32, j as f32 / n as f32);
                        let p = a + (b - a) * u + (c - a) * v;
                        if p.z < OBJECT_MIN_Z_M || p.z > ROBOT_BAND_M.1 {
                            continue;
                        }
                        if let Some(k) = grid.index(p.truncate()) {
                            grid.cells[k] = Cell::Occupied;
                        }
                    }
                }
            }
        }
        grid
    }

    /// Binary PGM (P5) as map_server reads it with `negate: 0`: occupied 0, free 254, unknown
    /// 205; the first image row is the top of the map (largest y).
    pub fn pgm_bytes(&self) -> Vec<u8> {
        let mut bytes = format!("P5\n{} {}\n255\n", self.width, self.height).into_bytes();
        for row in (0..self.height).rev() {
            bytes.extend(
                self.cells[row * self.width..(row + 1) * self.width]
                    .iter()
                    .map(|c| match c {
                        Cell::Occupied => 0u8,
                        Cell::Free => 254,
                        Cell::Unknown => 205,
                    }),
            );
        }
        bytes
    }

    /// The map_server YAML beside `image`.
    pub fn yaml_text(&self, image: &str) -> String {
        format!(
            "image: {image}\nmode: trinary\nresolution: {}\norigin: [{:.4}, {:.4}, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n",
            self.resolution, self.origin.x, self.origin.y
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2 m x 2 m floor with a 0.4 m box standing at (1, 1) and a table top at 0.7 m over
    /// (0.3..0.7, 1.2..1.6) whose legs were not seen.
    fn room() -> Vec<Vec3> {
        let mut points = Vec::new();
        for i in 0..=40 {
            for j in 0..=40 {
                points.push(Vec3::new(i as f32 * 0.05, j as f32 * 0.05, 0.0));
            }
        }
        for i in 0..=8 {
            for k in 1..=8 {
                points.push(Vec3::new(0.8 + i as f32 * 0.05, 0.81, k as f32 * 0.05));
            }
        }
        points
    }

    #[test]
    fn floor_is_free_and_what_stands_in_the_band_is_occupied() {
        let grid = OccupancyGrid::from_map(&room()).expect("points");
        let at = |x: f32, y: f32| grid.cells[grid.index(Vec2::new(x, y)).expect("inside")];
        assert_eq!(at(0.5, 0.5), Cell::Free);
        assert_eq!(at(1.0, 0.82), Cell::Occupied);
        assert_eq!(at(-0.02, 1.0), Cell::Unknown, "the margin beyond the floor");
        let top = TriMesh::cuboid(Vec3::new(0.3, 1.2, 0.68), Vec3::new(0.7, 1.6, 0.7));
        let objects = grid.with_objects(&[top]);
        assert_eq!(
            at(0.5, 1.4),
            Cell::Free,
            "the map layer does not see the table"
        );
        assert_eq!(
            objects.cells[objects.index(Vec2::new(0.5, 1.4)).expect("inside")],
            Cell::Occupied
        );
        let covered = objects.count(Cell::Occupied) - grid.count(Cell::Occupied);
        assert!(
            (60..=100).contains(&covered),
            "about 8 x 8 cells: {covered}"
        );
    }

    #[test]
    fn the_pgm_has_the_top_row_first_and_the_yaml_names_it() {
        let grid = OccupancyGrid::from_map(&room()).expect("points");
        let pgm = grid.pgm_bytes();
        let header = format!("P5\n{} {}\n255\n", grid.width, grid.height);
        assert!(pgm.starts_with(header.as_bytes()));
        assert_eq!(pgm.len(), header.len() + grid.width * grid.height);
        // The occupied wall at y = 0.81 shows in the image row counted from the top.
        let row_from_top = grid.height - 1 - ((0.81 - grid.origin.y) / grid.resolution) as usize;
        let col = ((1.0 - grid.origin.x) / grid.resolution) as usize;
        assert_eq!(pgm[header.len() + row_from_top * grid.width + col], 0);
        let yaml = grid.yaml_text("occupancy.pgm");
        assert!(yaml.starts_with("image: occupancy.pgm\n") && yaml.contains("resolution: 0.05"));
    }
}
