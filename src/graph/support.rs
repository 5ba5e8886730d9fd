//! Support relations, bottom-up (Han et al., Sect. 2): every object finds what holds it up
//! against gravity, from below if anything can, else from a wall it touches; then its box is
//! refined so the support holds exactly. The world is gravity-aligned: z up, floor at z = 0.

use glam::{Vec2, Vec3};

use crate::classes::EntityKind;
use crate::geometry::gravity_box::convex_overlap_area;
use crate::geometry::min_area_rect::convex_hull;
use crate::geometry::{GravityBox, Plane};

#[derive(Clone, Copy, Debug)]
pub struct SupportParams {
    /// A plane supports when its normal is this close to up (n . g <= -this, g = -z).
    pub up_normal: f32,
    /// A supporting plane may lie at most this far above the child's bottom (noise).
    pub above_tolerance: f32,
    /// Largest gap (metres) between a child's bottom and the plane that holds it; farther down,
    /// a plane does not hold the child (a wall cabinet does not stand on the cabinet under it).
    pub max_gap: f32,
    /// Share of the child's bottom area that must rest on the parent (stable support).
    pub min_area: f32,
    /// Parent vertices this close to a plane (metres) count as its surface.
    pub plane_band: f32,
    /// Cell of the grid on which surface area is counted (metres).
    pub area_cell: f32,
    /// A child this close to a wall (metres) touches it.
    pub wall_touch: f32,
    /// A parent's surface seen within this distance (metres) around a child's footprint counts
    /// as continuing under it, out to the outline of the surface (what stands on a table hides
    /// the table top under it).
    pub surface_reach: f32,
}

impl Default for SupportParams {
    fn default() -> Self {
        Self {
            up_normal: 0.9,
            above_tolerance: 0.04,
            max_gap: 0.1,
            min_area: 0.5,
            plane_band: 0.03,
            area_cell: 0.02,
            wall_touch: 0.05,
            surface_reach: 0.05,
        }
    }
}

/// What support inference needs of one entity.
pub struct SupportEntity<'a> {
    pub class: &'a str,
    pub kind: EntityKind,
    /// Movable things (floating joint: cups, chairs) stand on something; only fixed ones hang.
    pub movable: bool,
    pub bbox: GravityBox,
    pub planes: &'a [Plane],
    /// Mesh vertices, world frame.
    pub vertices: &'a [Vec3],
}

/// Who holds an entity, and the surface it rests on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SupportChoice {
    /// Rests on `plane` of `parent` (an index into the entities), `score` = (1 - min(1, D)) A.
    Below {
        parent: usize,
        plane: Plane,
        score: f32,
        /// The plane was not seen on the parent: the child's bottom stands in for it (an
        /// occluded table top), and belongs to the parent's planes from now on.
        registered: bool,
    },
    /// Hangs on the wall `parent`.
    Wall { parent: usize },
}

/// The support of every entity (`None` for layout and for objects nothing holds), in input order.
pub fn infer_supports(
    entities: &[SupportEntity],
    params: &SupportParams,
) -> Vec<Option<SupportChoice>> {
    let surfaces: Vec<Vec<UpwardSurface>> = entities
        .iter()
        .map(|e| upward_surfaces(e, params))
        .collect();
    entities
        .iter()
        .enumerate()
        .map(|(i, e)| {
            (e.kind != EntityKind::Layout).then(|| support_of(i, entities, &surfaces, params))?
        })
        .collect()
}

/// One upward plane of an entity with the surface points on it and their outline.
struct UpwardSurface {
    plane: Plane,
    points: Vec<Vec2>,
    /// Convex hull of `points`, counter-clockwise.
    outline: Vec<Vec2>,
}

/// The floor holds everywhere, not where its points are (`support_of`): its surfaces carry none.
fn upward_surfaces(entity: &SupportEntity, params: &SupportParams) -> Vec<UpwardSurface> {
    let by_points = entity.class != "floor";
    entity
        .planes
        .iter()
        .filter(|pl| pl.normal.z >= params.up_normal)
        .map(|&plane| {
            let points: Vec<Vec2> = entity
                .vertices
                .iter()
                .filter(|v| by_points && plane.signed_distance(**v).abs() <= params.plane_band)
                .map(|v| v.truncate())
                .collect();
            let outline = convex_hull(&points);
            UpwardSurface {
                plane,
                points,
                outline,
            }
        })
        .collect()
}

fn support_of(
    child: usize,
    entities: &[SupportEntity],
    surfaces: &[Vec<UpwardSurface>],
    params: &SupportParams,
) -> Option<SupportChoice> {
    let c = &entities[child];
    let bottom = c.bbox.bottom_z();
    let footprint = Footprint::of(&c.bbox);
    let mut best: Option<SupportChoice> = None;
    let mut consider = |choice: SupportChoice| {
        let score = |s: &SupportChoice| match s {
            SupportChoice::Below { score, .. } => *score,
            SupportChoice::Wall { .. } => 0.0,
        };
        if best.as_ref().is_none_or(|b| score(&choice) > score(b)) {
            best = Some(choice);
        }
    };
    for (p, parent) in entities.iter().enumerate() {
        if p == child || parent.bbox.bottom_z() >= bottom || parent.class == "ceiling" {
            continue;
        }
        // The floor is seen only around what stands on it, and a hand-held camera sees little
        // of it beyond the furniture (7-Scenes redkitchen's seen floor is 2 m wide, its chairs
        // stand outside it): it runs on under the whole room and holds whatever is over it.
        let layout_floor = parent.class == "floor";
        for surface in &surfaces[p] {
            let plane = &surface.plane;
            let height = plane_height(plane, c.bbox.center.truncate());
            if height > bottom + params.above_tolerance {
                continue;
            }
            let gap = bottom - height;
            if gap > params.max_gap && !layout_floor {
                continue;
            }
            let area = if layout_floor {
                1.0
            } else {
                let seen = footprint.covered_by(surface.points.iter().copied(), params.area_cell);
                // Where the surface is seen right around the child, it runs on under it to its
                // outline.
                let around = Footprint::of(&GravityBox {
                    size: footprint.bbox.size + Vec3::new(2.0, 2.0, 0.0) * params.surface_reach,
                    ..footprint.bbox
                });
                let continues = surface
                    .points
                    .iter()
                    .filter(|q| around.contains(**q) && !footprint.contains(**q))
                    .take(3)
                    .count()
                    == 3;
                if continues {
                    seen.max(
                        convex_overlap_area(&footprint.bbox.footprint(), &surface.outline)
                            / footprint.area().max(1e-9),
                    )
                } else {
                    seen
                }
            };
            if area >= params.min_area {
                consider(SupportChoice::Below {
                    parent: p,
                    plane: *plane,
                    score: (1.0 - gap.clamp(0.0, 1.0)) * area,
                    registered: false,
                });
            }
        }
    }
    if let Some(found @ SupportChoice::Below { plane, parent, .. }) = best {
        // Standing on the floor from high up means nothing near was found below: a wall the
        // child touches carries it instead (a wall cabinet above a counter).
        let hanging = entities[parent].class == "floor"
            && bottom - plane_height(&plane, c.bbox.center.truncate()) > params.max_gap;
        if !hanging {
            return Some(found);
        }
    }
    // No plane RANSAC listed holds the child. A parent's surface right under it may still do: a
    // shelf inside a cabinet (too small among the cabinet's planes), or a table top seen only
    // around what stands on it. Its height becomes a plane of the parent.
    let mut local: Option<(usize, f32, f32)> = None;
    for (p, parent) in entities.iter().enumerate() {
        if p == child || parent.kind == EntityKind::Layout || parent.bbox.bottom_z() >= bottom {
            continue;
        }
        let mut under: Vec<&Vec3> = parent
            .vertices
            .iter()
            .filter(|v| v.z >= bottom - params.max_gap && v.z <= bottom + params.above_tolerance)
            .filter(|v| footprint.contains(v.truncate()))
            .collect();
        let area = footprint.covered_by(under.iter().map(|v| v.truncate()), params.area_cell);
        if area < params.min_area {
            continue;
        }
        under.sort_by(|a, b| a.z.total_cmp(&b.z));
        let height = under[under.len() / 2].z;
        if local.is_none_or(|(_, h, _)| height > h) {
            local = Some((p, height, area));
        }
    }
    if let Some((parent, height, area)) = local {
        return Some(SupportChoice::Below {
            parent,
            plane: Plane::from_point_normal(Vec3::new(0.0, 0.0, height), Vec3::Z),
            score: (1.0 - (bottom - height).abs().min(1.0)) * area,
            registered: true,
        });
    }
    // Nothing of a parent was seen under the child: a parent whose box top meets the child's
    // bottom and whose footprint holds it lends its top (the table top hidden by what is on it).
    let mut occluded: Option<(usize, f32)> = None;
    for (p, parent) in entities.iter().enumerate() {
        if p == child || parent.kind == EntityKind::Layout {
            continue;
        }
        let top = parent.bbox.top_z();
        if (top - bottom).abs() > params.max_gap || parent.bbox.bottom_z() >= bottom {
            continue;
        }
        if footprint.overlap_with_box(&parent.bbox) >= params.min_area
            && occluded.is_none_or(|(_, t)| top > t)
        {
            occluded = Some((p, top));
        }
    }
    if let Some((parent, top)) = occluded {
        let area = footprint.overlap_with_box(&entities[parent].bbox);
        return Some(SupportChoice::Below {
            parent,
            plane: Plane::from_point_normal(Vec3::new(0.0, 0.0, top), Vec3::Z),
            score: (1.0 - (bottom - top).abs().min(1.0)) * area,
            registered: true,
        });
    }
    let wall = entities.iter().enumerate().find(|(_, w)| {
        !c.movable && w.class == "wall" && w.bbox.overlaps(&c.bbox, params.wall_touch)
    });
    if let Some((parent, _)) = wall {
        return Some(SupportChoice::Wall { parent });
    }
    // A movable object high over the floor and nothing near under it: the highest furniture top
    // under it holds it, however far below (a monitor whose stand was never seen stands on the
    // counter, not on the floor 1.2 m down).
    let floating = match best {
        Some(SupportChoice::Below { parent, plane, .. }) => {
            entities[parent].class == "floor"
                && bottom - plane_height(&plane, c.bbox.center.truncate()) > params.max_gap
        }
        _ => true,
    };
    if c.movable && floating {
        let under = entities
            .iter()
            .enumerate()
            .filter(|(p, parent)| {
                *p != child
                    && parent.kind != EntityKind::Layout
                    && parent.bbox.top_z() < bottom + params.above_tolerance
                    && footprint.overlap_with_box(&parent.bbox) >= params.min_area
            })
            .max_by(|a, b| a.1.bbox.top_z().total_cmp(&b.1.bbox.top_z()));
        let under = under.map(|(parent, holder)| (parent, holder.bbox.top_z()));
        // Or the board it stands on inside another's box, seen around it but hidden under it
        // (a bottle on a shelf's board, which the floor took, its box stretched 0.8 m down).
        let inside = board_inside(child, entities, params);
        let nearest = [under, inside]
            .into_iter()
            .flatten()
            .min_by(|a, b| (bottom - a.1).abs().total_cmp(&(bottom - b.1).abs()));
        if let Some((parent, height)) = nearest {
            return Some(SupportChoice::Below {
                parent,
                plane: Plane::from_point_normal(Vec3::new(0.0, 0.0, height), Vec3::Z),
                score: (1.0 - (bottom - height).abs().min(1.0))
                    * footprint.overlap_with_box(&entities[parent].bbox),
                registered: true,
            });
        }
    }
    // Nothing better: the floor, however far below (legs that were never seen).
    best
}

/// Grid cells (`area_cell` wide) holding a parent's surface seen beside a child's footprint
/// (within `surface_reach`), at one height (within `plane_band` of their median), that make the
/// board it stands on: a board's edge seen along a bottle is a row of them; a table's legs
/// beside a box under it are a cell or two each, at every height.
const BOARD_MIN_CELLS: usize = 4;

/// The object whose box the footprint of `child` stands in, from below its bottom to above it,
/// whose surface is seen beside the child's footprint at its bottom (within `max_gap` under it
/// or `above_tolerance` over it, in `BOARD_MIN_CELLS` at one height), and that height: the
/// board it stands on, hidden under it. The innermost such box (highest bottom) when several
/// hold it.
fn board_inside(
    child: usize,
    entities: &[SupportEntity],
    params: &SupportParams,
) -> Option<(usize, f32)> {
    let c = &entities[child];
    let bottom = c.bbox.bottom_z();
    let footprint = Footprint::of(&c.bbox);
    let ring = Footprint::of(&GravityBox {
        size: c.bbox.size + Vec3::new(2.0, 2.0, 0.0) * params.surface_reach,
        ..c.bbox
    });
    entities
        .iter()
        .enumerate()
        .filter(|(p, parent)| {
            *p != child
                && parent.kind != EntityKind::Layout
                && parent.bbox.bottom_z() < bottom
                && parent.bbox.top_z() > bottom + params.above_tolerance
                && footprint.overlap_with_box(&parent.bbox) >= params.min_area
        })
        .filter_map(|(p, parent)| {
            let beside: Vec<&Vec3> = parent
                .vertices
                .iter()
                .filter(|v| {
                    v.z >= bottom - params.max_gap && v.z <= bottom + params.above_tolerance
                })
                .filter(|v| ring.contains(v.truncate()) && !footprint.contains(v.truncate()))
                .collect();
            let mut heights: Vec<f32> = beside.iter().map(|v| v.z).collect();
            heights.sort_by(f32::total_cmp);
            let height = *heights.get(heights.len() / 2)?;
            let cells: std::collections::BTreeSet<(i32, i32)> = beside
                .iter()
                .filter(|v| (v.z - height).abs() <= params.plane_band)
                .map(|v| {
                    let cell = (v.truncate() / params.area_cell).floor();
                    (cell.x as i32, cell.y as i32)
                })
                .collect();
            (cells.len() >= BOARD_MIN_CELLS).then_some((p, parent.bbox.bottom_z(), height))
        })
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(p, _, height)| (p, height))
}

/// Height of `plane` above the floor point `xy` (planes here are near horizontal).
pub fn plane_height(plane: &Plane, xy: Vec2) -> f32 {
    -(plane.normal.x * xy.x + plane.normal.y * xy.y + plane.offset) / plane.normal.z
}

/// The child's bottom rectangle, sampled on a grid to measure what covers it.
struct Footprint {
    bbox: GravityBox,
}

impl Footprint {
    fn of(bbox: &GravityBox) -> Self {
        Self { bbox: *bbox }
    }

    fn area(&self) -> f32 {
        self.bbox.size.x * self.bbox.size.y
    }

    fn contains(&self, p: Vec2) -> bool {
        let l = self.local(p);
        l.x.abs() <= 0.5 * self.bbox.size.x && l.y.abs() <= 0.5 * self.bbox.size.y
    }

    fn local(&self, p: Vec2) -> Vec2 {
        let axis = Vec2::from_angle(self.bbox.yaw);
        let d = p - self.bbox.center.truncate();
        Vec2::new(d.dot(axis), d.dot(axis.perp()))
    }

    /// Share of the footprint whose grid cells hold at least one of `points`.
    fn covered_by(&self, points: impl Iterator<Item = Vec2>, cell: f32) -> f32 {
        let half = self.bbox.size.truncate() * 0.5;
        let cells = (self.bbox.size.truncate() / cell)
            .ceil()
            .max(Vec2::ONE)
            .as_uvec2();
        let mut hit = vec![false; (cells.x * cells.y) as usize];
        for p in points {
            let l = self.local(p) + half;
            if l.x < 0.0 || l.y < 0.0 || l.x >= self.bbox.size.x || l.y >= self.bbox.size.y {
                continue;
            }
            let (i, j) = ((l.x / cell) as u32, (l.y / cell) as u32);
            hit[(j.min(cells.y - 1) * cells.x + i.min(cells.x - 1)) as usize] = true;
        }
        let covered = hit.iter().filter(|h| **h).count() as f32 * cell * cell;
        (covered / self.area().max(1e-6)).min(1.0)
    }

    /// Share of the footprint inside `other`'s footprint, on an 8 x 8 sample grid.
    fn overlap_with_box(&self, other: &GravityBox) -> f32 {
        const N: usize = 8;
        let axis = Vec2::from_angle(self.bbox.yaw);
        let other_axis = Vec2::from_angle(other.yaw);
        let mut inside = 0;
        for i in 0..N {
            for j in 0..N {
                let u = ((i as f32 + 0.5) / N as f32 - 0.5) * self.bbox.size.x;
                let v = ((j as f32 + 0.5) / N as f32 - 0.5) * self.bbox.size.y;
                let p = self.bbox.center.truncate() + axis * u + axis.perp() * v;
                let d = p - other.center.truncate();
                if d.dot(other_axis).abs() <= 0.5 * other.size.x
                    && d.dot(other_axis.perp()).abs() <= 0.5 * other.size.y
                {
                    inside += 1;
                }
            }
        }
        inside as f32 / (N * N) as f32
    }
}

/// `bbox` stretched or trimmed so its bottom lies on `plane` (the chair whose legs were not
/// seen reaches the floor; a box sunk into its table by noise is lifted out).
pub fn rest_on(bbox: &GravityBox, plane: &Plane) -> GravityBox {
    let height = plane_height(plane, bbox.center.truncate());
    let top = bbox.top_z();
    if top <= height {
        return *bbox;
    }
    GravityBox {
        center: bbox.center.truncate().extend(0.5 * (top + height)),
        yaw: bbox.yaw,
        size: bbox.size.truncate().extend(top - height),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn slab(center: Vec3, size: Vec3) -> GravityBox {
        GravityBox {
            center,
            yaw: 0.0,
            size,
        }
    }

    /// Vertices on the top face of a box, 1 cm apart.
    fn top_vertices(b: &GravityBox) -> Vec<Vec3> {
        let mut v = Vec::new();
        let n = (b.size.truncate() / 0.01).as_uvec2();
        for i in 0..=n.x {
            for j in 0..=n.y {
                v.push(Vec3::new(
                    b.center.x - 0.5 * b.size.x + i as f32 * 0.01,
                    b.center.y - 0.5 * b.size.y + j as f32 * 0.01,
                    b.top_z(),
                ));
            }
        }
        v
    }

    /// The floor (layout), a fixed parent and a movable child, in that order.
    fn floor_parent_child<'a>(
        classes: &[&'a str; 3],
        boxes: &[GravityBox; 3],
        planes: &'a [Vec<Plane>; 3],
        vertices: &'a [Vec<Vec3>; 3],
    ) -> Vec<SupportEntity<'a>> {
        (0..3)
            .map(|i| SupportEntity {
                class: classes[i],
                kind: if i == 0 {
                    EntityKind::Layout
                } else {
                    EntityKind::Rigid
                },
                movable: i == 2,
                bbox: boxes[i],
                planes: &planes[i],
                vertices: &vertices[i],
            })
            .collect()
    }

    #[test]
    fn a_cup_rests_on_the_table_a_wall_cabinet_hangs_and_an_occluded_top_is_registered() {
        let floor = slab(Vec3::new(2.0, 2.0, -0.05), Vec3::new(4.0, 4.0, 0.1));
        let wall = slab(Vec3::new(2.0, 4.05, 1.3), Vec3::new(4.0, 0.1, 2.6));
        let table = slab(Vec3::new(1.0, 1.0, 0.375), Vec3::new(1.2, 0.8, 0.75));
        let cup = slab(Vec3::new(1.1, 0.9, 0.8), Vec3::new(0.08, 0.08, 0.1));
        let base = slab(Vec3::new(2.5, 3.7, 0.45), Vec3::new(0.6, 0.6, 0.9));
        let hanging = slab(Vec3::new(2.5, 3.8, 1.8), Vec3::new(0.6, 0.4, 0.7));
        // A microwave whose cabinet's top was never seen (no vertices, no plane).
        let cabinet = slab(Vec3::new(3.5, 1.0, 0.45), Vec3::new(0.6, 0.6, 0.9));
        let microwave = slab(Vec3::new(3.5, 1.0, 1.05), Vec3::new(0.5, 0.4, 0.3));
        let up = |b: &GravityBox| Plane::from_point_normal(Vec3::new(0.0, 0.0, b.top_z()), Vec3::Z);
        let planes = [
            vec![up(&floor)],
            vec![Plane::from_point_normal(Vec3::new(0.0, 4.0, 0.0), -Vec3::Y)],
            vec![up(&table)],
            vec![up(&cup)],
            vec![up(&base)],
            vec![],
            vec![],
            vec![up(&microwave)],
        ];
        let vertices = [
            vec![],
            vec![],
            top_vertices(&table),
            top_vertices(&cup),
            top_vertices(&base),
            vec![],
            vec![],
            top_vertices(&microwave),
        ];
        let kinds = [EntityKind::Layout, EntityKind::Layout];
        let boxes = [floor, wall, table, cup, base, hanging, cabinet, microwave];
        let classes = [
            "floor",
            "wall",
            "table",
            "cup",
            "cabinet",
            "cabinet",
            "cabinet",
            "microwave",
        ];
        let entities: Vec<SupportEntity> = (0..boxes.len())
            .map(|i| SupportEntity {
                class: classes[i],
                kind: kinds.get(i).copied().unwrap_or(EntityKind::Rigid),
                movable: classes[i] == "cup",
                bbox: boxes[i],
                planes: &planes[i],
                vertices: &vertices[i],
            })
            .collect();
        let supports = infer_supports(&entities, &SupportParams::default());
        let parent = |i: usize| match supports[i] {
            Some(SupportChoice::Below { parent, .. }) | Some(SupportChoice::Wall { parent }) => {
                Some(parent)
            }
            None => None,
        };
        assert_eq!(parent(0), None);
        assert_eq!(parent(1), None);
        assert_eq!(parent(2), Some(0), "table on the floor");
        assert_eq!(parent(3), Some(2), "cup on the table");
        assert_eq!(parent(4), Some(0), "base cabinet on the floor");
        assert_eq!(
            supports[5],
            Some(SupportChoice::Wall { parent: 1 }),
            "wall cabinet on the wall"
        );
        assert_eq!(parent(6), Some(0));
        assert!(
            matches!(
                supports[7],
                Some(SupportChoice::Below {
                    parent: 6,
                    registered: true,
                    ..
                })
            ),
            "{:?}",
            supports[7]
        );
    }

    #[test]
    fn a_monitor_whose_stand_was_not_seen_stands_on_the_counter_under_it() {
        let floor = slab(Vec3::new(2.0, 2.0, -0.05), Vec3::new(4.0, 4.0, 0.1));
        let counter = slab(Vec3::new(1.0, 3.5, 0.45), Vec3::new(2.0, 0.6, 0.9));
        // The screen alone, 30 cm above the counter top.
        let monitor = slab(Vec3::new(1.0, 3.5, 1.4), Vec3::new(0.6, 0.15, 0.4));
        let up = |b: &GravityBox| Plane::from_point_normal(Vec3::new(0.0, 0.0, b.top_z()), Vec3::Z);
        let planes = [vec![up(&floor)], vec![up(&counter)], vec![]];
        let vertices = [vec![], top_vertices(&counter), vec![]];
        let boxes = [floor, counter, monitor];
        let classes = ["floor", "counter", "monitor"];
        let entities = floor_parent_child(&classes, &boxes, &planes, &vertices);
        let supports = infer_supports(&entities, &SupportParams::default());
        match supports[2] {
            Some(SupportChoice::Below { parent, plane, .. }) => {
                assert_eq!(parent, 1, "on the counter, not the floor");
                assert!((plane_height(&plane, Vec2::ZERO) - 0.9).abs() < 1e-4);
            }
            other => panic!("{other:?}"),
        }
        // Not movable (a wall cabinet with no wall near): the floor, as before.
        let fixed: Vec<SupportEntity> = entities
            .into_iter()
            .map(|e| SupportEntity {
                movable: false,
                ..e
            })
            .collect();
        let supports = infer_supports(&fixed, &SupportParams::default());
        assert!(
            matches!(supports[2], Some(SupportChoice::Below { parent: 0, .. })),
            "{:?}",
            supports[2]
        );
    }

    #[test]
    fn a_bottle_on_a_shelf_board_hidden_under_it_stands_in_the_shelf_not_on_the_floor() {
        let floor = slab(Vec3::new(2.0, 2.0, -0.05), Vec3::new(4.0, 4.0, 0.1));
        // A shelf 1.6 m tall whose board at 0.82 m is seen only as its front edge, a row of
        // vertices beside the bottle; its other surfaces are the sides and top.
        let shelf = slab(Vec3::new(1.0, 1.0, 0.8), Vec3::new(0.9, 0.4, 1.6));
        let mut shelf_vertices = top_vertices(&shelf);
        shelf_vertices.extend((0..30).map(|i| Vec3::new(0.7 + 0.01 * i as f32, 0.82, 0.82)));
        let bottle = slab(Vec3::new(0.85, 0.9, 0.93), Vec3::new(0.07, 0.07, 0.22));
        let up = |b: &GravityBox| Plane::from_point_normal(Vec3::new(0.0, 0.0, b.top_z()), Vec3::Z);
        let planes = [vec![up(&floor)], vec![up(&shelf)], vec![]];
        let vertices = [vec![], shelf_vertices, vec![]];
        let boxes = [floor, shelf, bottle];
        let classes = ["floor", "shelf", "bottle"];
        let entities = floor_parent_child(&classes, &boxes, &planes, &vertices);
        match infer_supports(&entities, &SupportParams::default())[2] {
            Some(SupportChoice::Below {
                parent,
                plane,
                registered,
                ..
            }) => {
                assert_eq!(parent, 1, "in the shelf, not on the floor");
                assert!((plane_height(&plane, Vec2::ZERO) - 0.82).abs() < 1e-4);
                assert!(registered);
            }
            other => panic!("{other:?}"),
        }
        // A box under a table, its bottom unseen, two of the table's legs beside it: a cell each
        // at every height make no board, and the floor holds it.
        let table = slab(Vec3::new(1.0, 1.0, 0.375), Vec3::new(1.2, 0.8, 0.75));
        let mut table_vertices = top_vertices(&table);
        table_vertices.extend((0..75).map(|i| Vec3::new(0.42, 0.62, 0.01 * i as f32)));
        table_vertices.extend((0..75).map(|i| Vec3::new(0.58, 0.62, 0.01 * i as f32)));
        let low_box = slab(Vec3::new(0.5, 0.7, 0.3), Vec3::new(0.12, 0.12, 0.2));
        let planes = [vec![up(&floor)], vec![up(&table)], vec![]];
        let vertices = [vec![], table_vertices, vec![]];
        let boxes = [floor, table, low_box];
        let classes = ["floor", "table", "box"];
        let entities = floor_parent_child(&classes, &boxes, &planes, &vertices);
        assert!(
            matches!(
                infer_supports(&entities, &SupportParams::default())[2],
                Some(SupportChoice::Below { parent: 0, .. })
            ),
            "on the floor"
        );
    }

    #[test]
    fn a_book_hiding_the_table_top_rests_on_the_table_plane() {
        let floor = slab(Vec3::new(2.0, 2.0, -0.05), Vec3::new(4.0, 4.0, 0.1));
        let table = slab(Vec3::new(1.0, 1.0, 0.375), Vec3::new(1.2, 0.8, 0.75));
        // Only the book's top was seen, 4 cm above the table (beyond the plane's band).
        let book = slab(Vec3::new(1.1, 0.9, 0.79), Vec3::new(0.2, 0.15, 0.0));
        let up = |b: &GravityBox| Plane::from_point_normal(Vec3::new(0.0, 0.0, b.top_z()), Vec3::Z);
        // The table top is seen around the book, not under it; a strip of the book's top took
        // the table's label (bleeding), so "the table's surface under the book" is up there.
        let footprint = Footprint::of(&book);
        let mut table_vertices: Vec<Vec3> = top_vertices(&table)
            .into_iter()
            .filter(|v| !footprint.contains(v.truncate()))
            .collect();
        table_vertices.extend(
            top_vertices(&book)
                .into_iter()
                .map(|v| v.with_z(book.top_z())),
        );
        let planes = [vec![up(&floor)], vec![up(&table)], vec![up(&book)]];
        let vertices = [vec![], table_vertices, top_vertices(&book)];
        let boxes = [floor, table, book];
        let classes = ["floor", "table", "book"];
        let entities = floor_parent_child(&classes, &boxes, &planes, &vertices);
        let supports = infer_supports(&entities, &SupportParams::default());
        let Some(SupportChoice::Below {
            parent,
            plane,
            registered,
            ..
        }) = supports[2]
        else {
            panic!("the book is not held from below: {:?}", supports[2]);
        };
        assert_eq!((parent, registered), (1, false), "on the table's own plane");
        let rested = rest_on(&book, &plane);
        assert!((rested.bottom_z() - 0.75).abs() < 1e-5, "{rested:?}");
    }

    #[test]
    fn a_floating_box_is_stretched_down_to_its_plane() {
        let b = slab(Vec3::new(0.0, 0.0, 0.6), Vec3::new(0.5, 0.5, 0.4));
        let r = rest_on(&b, &Plane::from_point_normal(Vec3::ZERO, Vec3::Z));
        assert!((r.bottom_z()).abs() < 1e-6 && (r.top_z() - 0.8).abs() < 1e-6);
        let sunk = slab(Vec3::new(0.0, 0.0, 0.74), Vec3::new(0.1, 0.1, 0.1));
        let lifted = rest_on(
            &sunk,
            &Plane::from_point_normal(Vec3::new(0.0, 0.0, 0.75), Vec3::Z),
        );
        assert!((lifted.bottom_z() - 0.75).abs() < 1e-6 && (lifted.top_z() - 0.79).abs() < 1e-6);
    }
}
