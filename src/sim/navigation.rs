//! Navigation for the round base: the object-projected occupancy grid of the scene as it stands
//! now, each cell's clearance to the nearest obstacle, and A* to the nearest cell from which
//! the robot reaches its target.
//!
//! Shape-aware in the sense of Sivananda et al.: obstacles are the complete models projected
//! onto the floor between 0.1 m and the robot's height (a table top blocks the base, not just
//! its legs), and a cell is a place for the base only when its clearance is at least the base's
//! radius. Cells a little farther from obstacles cost less, so paths keep off the furniture.

use glam::{Vec2, Vec3};
use pathfinding::prelude::astar;

use crate::export::occupancy::{Cell, OccupancyGrid};
use crate::geometry::TriMesh;

/// Beyond the base's radius, clearance up to this much more (metres) is paid for.
const COMFORT_M: f32 = 0.15;
/// Cost (per metre of missing comfort, per metre walked) of passing close to obstacles.
const CLOSENESS_COST: f32 = 4.0;

/// The grid the base plans on, with every cell's distance to the nearest blocked cell.
#[derive(Clone, Debug)]
pub struct NavGrid {
    pub grid: OccupancyGrid,
    /// Metres from each cell's centre to the nearest cell that is not free (capped).
    pub clearance: Vec<f32>,
    /// The room's walls as segments on the floor (their middle planes): a base never works
    /// across one. A reconstructed floor can reach past a wall (7-Scenes' kitchen: 50 cm behind
    /// the counter's wall), and the cell nearest a target may lie behind it, where the arm
    /// meets the wall.
    pub walls: Vec<(Vec2, Vec2)>,
}

/// Where the base must end: within `reach` of `target`, optionally on the `facing` side of it
/// (in front of a door), and away from `keep_out` discs (where a door swings).
#[derive(Clone, Debug, PartialEq)]
pub struct NavGoal {
    pub target: Vec2,
    pub reach: f32,
    /// Unit vector: the base must stand where `(p - target) . facing > 0`.
    pub facing: Option<Vec2>,
    /// Discs (centre, radius) the base's centre must stay out of.
    pub keep_out: Vec<(Vec2, f32)>,
}

impl NavGoal {
    /// Whether a base centred at `p` satisfies the goal.
    pub fn is_met(&self, p: Vec2) -> bool {
        let d = p - self.target;
        d.length() <= self.reach
            && self.facing.is_none_or(|f| d.dot(f) > 0.0)
            && self.keep_out.iter().all(|(c, r)| p.distance(*c) >= *r)
    }
}

/// A path of base positions (cell centres) from the start to the goal, and its length.
#[derive(Clone, Debug, PartialEq)]
pub struct NavPath {
    pub waypoints: Vec<Vec2>,
    pub length_m: f32,
}

impl NavGrid {
    /// Free where the floor is, blocked where any of `obstacles` (world frame) has surface
    /// in the robot's height band (0.1 to 1.5 m, `OccupancyGrid::with_objects`). `floor` gives
    /// the walkable extent.
    pub fn new(floor: &TriMesh, obstacles: &[TriMesh]) -> Option<Self> {
        let (lo, hi) = floor.bounds()?;
        let corners = [Vec3::new(lo.x, lo.y, 0.0), Vec3::new(hi.x, hi.y, 0.0)];
        let mut grid = OccupancyGrid::from_map(&corners)?;
        // Every cell over the floor's extent is floor.
        for row in 0..grid.height {
            for col in 0..grid.width {
                let c = grid.origin + (Vec2::new(col as f32, row as f32) + 0.5) * grid.resolution;
                if c.cmpge(lo.truncate()).all() && c.cmple(hi.truncate()).all() {
                    grid.cells[row * grid.width + col] = Cell::Free;
                }
            }
        }
        let grid = grid.with_objects(obstacles);
        let clearance = clearance_of(&grid, 1.0);
        Some(Self {
            grid,
            clearance,
            walls: Vec::new(),
        })
    }

    /// This grid with the room's `walls` (segments on the floor).
    pub fn with_walls(self, walls: Vec<(Vec2, Vec2)>) -> Self {
        Self { walls, ..self }
    }

    /// Whether the straight line from `a` to `b` crosses a wall.
    fn across_a_wall(&self, a: Vec2, b: Vec2) -> bool {
        self.walls
            .iter()
            .any(|&(p, q)| segments_cross((a, b), (p, q)))
    }

    fn cell_of(&self, p: Vec2) -> Option<(usize, usize)> {
        let i = self.grid.index(p)?;
        Some((i % self.grid.width, i / self.grid.width))
    }

    fn center(&self, (col, row): (usize, usize)) -> Vec2 {
        self.grid.origin + (Vec2::new(col as f32, row as f32) + 0.5) * self.grid.resolution
    }

    /// The clearance at `p`, metres (0 outside the grid).
    pub fn clearance_at(&self, p: Vec2) -> f32 {
        self.grid.index(p).map_or(0.0, |i| self.clearance[i])
    }

    /// The free cell with the most clearance (the first such in row order): a default start.
    pub fn most_open(&self) -> Option<Vec2> {
        let (i, _) = self.clearance.iter().enumerate().fold(
            None::<(usize, f32)>,
            |best, (i, c)| match best {
                Some((_, b)) if b >= *c => best,
                _ => Some((i, *c)),
            },
        )?;
        Some(self.center((i % self.grid.width, i / self.grid.width)))
    }

    /// The cheapest path for a base of `radius` from `start` to a cell satisfying `goal`, or
    /// `None` when there is none. The start cell may be tighter than `radius` (the robot may
    /// begin close to something: a drawer it opened over its base), and so may the cells
    /// within `radius` of it that are no tighter (it backs out the way it came); every other
    /// cell on the path may not.
    pub fn plan(&self, start: Vec2, goal: &NavGoal, radius: f32) -> Option<NavPath> {
        let start_cell = self.cell_of(start)?;
        let res = self.grid.resolution;
        let start_clearance = self.clearance[start_cell.1 * self.grid.width + start_cell.0];
        let backing_out = |cell: (usize, usize), clearance: f32| {
            clearance > 0.0
                && clearance >= start_clearance
                && self.center(cell).distance(start) <= radius
        };
        let mm = |m: f32| (m * 1000.0).round() as u32;
        let (cells, _cost) = astar(
            &start_cell,
            |&(col, row)| {
                let mut next = Vec::with_capacity(8);
                for (dc, dr) in [
                    (-1i64, -1i64),
                    (0, -1),
                    (1, -1),
                    (-1, 0),
                    (1, 0),
                    (-1, 1),
                    (0, 1),
                    (1, 1),
                ] {
                    let (c, r) = (col as i64 + dc, row as i64 + dr);
                    if c < 0 || r < 0 || c >= self.grid.width as i64 || r >= self.grid.height as i64
                    {
                        continue;
                    }
                    let (c, r) = (c as usize, r as usize);
                    let clearance = self.clearance[r * self.grid.width + c];
                    if clearance < radius && !backing_out((c, r), clearance) {
                        continue;
                    }
                    let step = res * ((dc * dc + dr * dr) as f32).sqrt();
                    let tight = (radius + COMFORT_M - clearance).max(0.0);
                    next.push(((c, r), mm(step * (1.0 + CLOSENESS_COST * tight))));
                }
                next
            },
            |&cell| mm((self.center(cell).distance(goal.target) - goal.reach - res).max(0.0)),
            |&cell| {
                let c = self.center(cell);
                goal.is_met(c) && !self.across_a_wall(c, goal.target)
            },
        )?;
        let waypoints: Vec<Vec2> = cells.iter().map(|c| self.center(*c)).collect();
        let length_m = waypoints.windows(2).map(|w| w[0].distance(w[1])).sum();
        Some(NavPath {
            waypoints,
            length_m,
        })
    }
}

/// Whether segments `a` and `b` cross (touching counts).
fn segments_cross(a: (Vec2, Vec2), b: (Vec2, Vec2)) -> bool {
    let side = |p: Vec2, q: Vec2, r: Vec2| (q - p).perp_dot(r - p);
    let (d1, d2) = (side(b.0, b.1, a.0), side(b.0, b.1, a.1));
    let (d3, d4) = (side(a.0, a.1, b.0), side(a.0, a.1, b.1));
    d1 * d2 <= 0.0 && d3 * d4 <= 0.0 && !(d1 == 0.0 && d2 == 0.0)
}

/// Each cell's distance to the nearest cell that is not free, up to `cap` metres: every blocked
/// cell stamps a disc of `cap` around it.
fn clearance_of(grid: &OccupancyGrid, cap: f32) -> Vec<f32> {
    let res = grid.resolution;
    let mut clearance = vec![cap; grid.cells.len()];
    let k = (cap / res).ceil() as i64;
    let (w, h) = (grid.width as i64, grid.height as i64);
    for (i, cell) in grid.cells.iter().enumerate() {
        if *cell == Cell::Free {
            continue;
        }
        let (col, row) = ((i as i64) % w, (i as i64) / w);
        for dr in -k..=k {
            for dc in -k..=k {
                let (c, r) = (col + dc, row + dr);
                if c < 0 || r < 0 || c >= w || r >= h {
                    continue;
                }
                // From the free cell's centre to the blocked cell's nearest edge.
                let gap = |d: i64| (d.abs() as f32 - 0.5).max(0.0) * res;
                let d = gap(dc).hypot(gap(dr));
                let j = (r * w + c) as usize;
                clearance[j] = clearance[j].min(d);
            }
        }
    }
    // Outside the grid is blocked too.
    for (i, c) in clearance.iter_mut().enumerate() {
        let (col, row) = ((i as i64) % w, (i as i64) / w);
        let edge = col.min(row).min(w - 1 - col).min(h - 1 - row) as f32 * res + 0.5 * res;
        *c = c.min(edge);
    }
    clearance
}

#[cfg(test)]
mod tests {
    use super::*;

    fn room_with_block() -> NavGrid {
        let floor = TriMesh::cuboid(Vec3::new(0.0, 0.0, -0.05), Vec3::new(4.0, 3.0, 0.0));
        // A 1 m block in the middle of the room, and the four walls.
        let obstacles = vec![
            TriMesh::cuboid(Vec3::new(1.5, 1.0, 0.0), Vec3::new(2.5, 2.0, 0.8)),
            TriMesh::cuboid(Vec3::new(-0.1, -0.1, 0.0), Vec3::new(4.1, 0.0, 2.5)),
            TriMesh::cuboid(Vec3::new(-0.1, 3.0, 0.0), Vec3::new(4.1, 3.1, 2.5)),
            TriMesh::cuboid(Vec3::new(-0.1, 0.0, 0.0), Vec3::new(0.0, 3.0, 2.5)),
            TriMesh::cuboid(Vec3::new(4.0, 0.0, 0.0), Vec3::new(4.1, 3.0, 2.5)),
        ];
        NavGrid::new(&floor, &obstacles).expect("grid")
    }

    #[test]
    fn clearance_is_the_distance_to_the_nearest_obstacle() {
        let nav = room_with_block();
        // 0.5 m left of the block, 1 m from the left wall.
        let c = nav.clearance_at(Vec2::new(1.0, 1.5));
        assert!((c - 0.5).abs() <= 0.05, "{c}");
        assert!(nav.clearance_at(Vec2::new(2.0, 1.5)) == 0.0);
    }

    #[test]
    fn the_path_goes_around_the_block_and_keeps_the_base_clear() {
        let nav = room_with_block();
        let goal = NavGoal {
            target: Vec2::new(3.5, 1.5),
            reach: 0.2,
            facing: None,
            keep_out: Vec::new(),
        };
        let path = nav.plan(Vec2::new(0.5, 1.5), &goal, 0.25).expect("path");
        let end = *path.waypoints.last().expect("end");
        assert!(end.distance(goal.target) <= 0.2, "{end}");
        for p in &path.waypoints[1..] {
            assert!(nav.clearance_at(*p) >= 0.25, "{p} too close");
        }
        // Straight through would be 2.8 m; around the block is longer, but not absurdly.
        assert!(
            path.length_m > 3.0 && path.length_m < 4.5,
            "{}",
            path.length_m
        );
    }

    #[test]
    fn a_base_closer_to_the_block_than_its_radius_backs_out_and_no_nearer() {
        let nav = room_with_block();
        let goal = NavGoal {
            target: Vec2::new(0.5, 0.5),
            reach: 0.2,
            facing: None,
            keep_out: Vec::new(),
        };
        // 12 cm from the block's left face (a drawer opened over the base): every cell around
        // is tighter than the 25 cm radius.
        let start = Vec2::new(1.38, 1.5);
        let path = nav.plan(start, &goal, 0.25).expect("it backs out");
        let tight = nav.clearance_at(start);
        assert!(tight < 0.15, "{tight}");
        for p in &path.waypoints[1..] {
            let c = nav.clearance_at(*p);
            assert!(c >= 0.25 || c >= tight, "{p} nearer the block ({c} m)");
            assert!(
                c >= 0.25 || p.distance(start) <= 0.25,
                "{p} tight, far from the start"
            );
        }
        // It does not squeeze past the block's corner it starts beside.
        let past = NavGoal {
            target: Vec2::new(1.38, 2.6),
            reach: 0.05,
            ..goal
        };
        if let Some(path) = nav.plan(start, &past, 0.25) {
            for p in &path.waypoints[1..] {
                let c = nav.clearance_at(*p);
                assert!(c >= 0.25 || p.distance(start) <= 0.25, "{p} ({c} m)");
            }
        }
    }

    #[test]
    fn a_goal_the_base_cannot_reach_has_no_path() {
        let nav = room_with_block();
        let goal = NavGoal {
            target: Vec2::new(2.0, 1.5),
            reach: 0.3,
            facing: None,
            keep_out: Vec::new(),
        };
        assert!(nav.plan(Vec2::new(0.5, 1.5), &goal, 0.25).is_none());
    }

    #[test]
    fn the_base_never_stands_across_a_wall_from_its_target() {
        // A room 4 m deep whose floor runs on past a wall at y = 3 (with a gap at its right end):
        // the target stands against the wall's near side.
        let floor = TriMesh::cuboid(Vec3::new(0.0, 0.0, -0.05), Vec3::new(4.0, 4.0, 0.0));
        let wall = TriMesh::cuboid(Vec3::new(0.0, 2.95, 0.0), Vec3::new(3.0, 3.05, 2.5));
        let nav = NavGrid::new(&floor, &[wall]).expect("grid");
        let goal = NavGoal {
            target: Vec2::new(1.5, 2.8),
            reach: 0.8,
            facing: None,
            keep_out: Vec::new(),
        };
        // From behind the wall the nearest cell within reach is behind it too, 0.5 m away.
        let behind = Vec2::new(1.5, 3.6);
        let end = |nav: &NavGrid| {
            *nav.plan(behind, &goal, 0.25)
                .expect("path")
                .waypoints
                .last()
                .expect("end")
        };
        assert!(end(&nav).y > 3.0, "{}", end(&nav));
        let nav = nav.with_walls(vec![(Vec2::new(0.0, 3.0), Vec2::new(3.0, 3.0))]);
        let there = end(&nav);
        assert!(
            there.y < 2.95 && there.distance(goal.target) <= 0.8,
            "{there}"
        );
    }

    #[test]
    fn segments_cross_where_they_meet() {
        let (o, x, y) = (Vec2::ZERO, Vec2::X, Vec2::Y);
        assert!(segments_cross((o, x + y), (x, y)));
        assert!(!segments_cross((o, x), (y, x + y)));
        assert!(!segments_cross((o, 0.4 * (x + y)), (x, y)));
    }

    #[test]
    fn facing_and_keep_out_push_the_goal_cell_around() {
        let nav = room_with_block();
        let goal = NavGoal {
            target: Vec2::new(2.0, 2.0),
            reach: 0.9,
            facing: Some(Vec2::Y),
            keep_out: vec![(Vec2::new(2.0, 2.3), 0.4)],
        };
        let path = nav.plan(Vec2::new(0.5, 0.5), &goal, 0.25).expect("path");
        let end = *path.waypoints.last().expect("end");
        assert!(
            end.y > 2.0 && end.distance(Vec2::new(2.0, 2.3)) >= 0.4,
            "{end}"
        );
    }
}
