//! Support relations, bottom-up (Han et al., Sect. 2): every object finds what holds it up
//! against gravity, from below if anything can, else from a wall it touches; then its box is
//! refined so the support holds exactly. The world is gravity-aligned: z up, floor at z = 0.

use glam::{Vec2, Vec3};

use crate::classes::EntityKind;
use crate::geometry::gravity_box::convex_overlap_area;
use crate::geometry::min_area_rect::convex_hull;
use crate::geometry::{GravityBox, Plane};

mod board;
mod footprint;
#[cfg(test)]
mod tests;

use board::board_inside;
use footprint::Footprint;

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
    /// A unit whose box comes this close (metres) to a child's that nothing else holds, its top
    /// at the child's bottom, holds it (`support_of`'s last resort before the floor).
    pub beside_reach: f32,
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
            beside_reach: 0.1,
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
    // Nothing under it at all, high over the floor: a unit (a cabinet, an appliance) right
    // beside it whose top meets its bottom holds it. In a row of kitchen units a microwave
    // standing on one hides its top, and its neighbours hide its sides: the unit is seen as its
    // front alone, a slab beside the microwave, not under it (rooms 5, 16, 30 and 42 of
    // `iscene benchmark`: the microwave went to the floor 0.8 m down, its box with it). Only a
    // unit: a table whose legs were never seen stands on the floor, not on the chair beside it
    // whose back is as high (room 42).
    if floating && let Some(parent) = unit_beside(child, entities, params) {
        let top = entities[parent].bbox.top_z();
        return Some(SupportChoice::Below {
            parent,
            plane: Plane::from_point_normal(Vec3::new(0.0, 0.0, top), Vec3::Z),
            score: 0.0,
            registered: true,
        });
    }
    // Nothing better: the floor, however far below (legs that were never seen).
    best
}

/// The unit (an articulated object) whose box top lies within `max_gap` of `child`'s bottom,
/// under its top, whose box comes within `beside_reach` of the child's: the one whose top is
/// nearest the child's bottom, the first of equals.
fn unit_beside(child: usize, entities: &[SupportEntity], params: &SupportParams) -> Option<usize> {
    let c = &entities[child];
    let bottom = c.bbox.bottom_z();
    entities
        .iter()
        .enumerate()
        .filter(|(p, parent)| {
            *p != child
                && parent.kind == EntityKind::Articulated
                && parent.bbox.bottom_z() < bottom
                && (parent.bbox.top_z() - bottom).abs() <= params.max_gap
                && parent.bbox.overlaps(&c.bbox, params.beside_reach)
        })
        .min_by(|a, b| {
            let gap = |e: &SupportEntity| (e.bbox.top_z() - bottom).abs();
            gap(a.1).total_cmp(&gap(b.1))
        })
        .map(|(p, _)| p)
}

/// Height of `plane` above the floor point `xy` (planes here are near horizontal).
pub fn plane_height(plane: &Plane, xy: Vec2) -> f32 {
    -(plane.normal.x * xy.x + plane.normal.y * xy.y + plane.offset) / plane.normal.z
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
