//! Proximal pairs: two entities close without either supporting the other, so their meshes must
//! not interpenetrate (the CAD stage's constraint). Bevy's relationships are one-to-many, and an
//! object can be proximal to several others, so each pair is an entity of its own (a junction
//! entity, as a many-to-many relation is a junction table): `ProximalEndA` relates it to one end
//! and `ProximalEndB` to the other, and despawning either end despawns the pair.

use bevy::prelude::*;

/// A proximal pair's first end.
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq)]
#[relationship(relationship_target = ProximalPairsAsA)]
pub struct ProximalEndA(pub Entity);

/// A proximal pair's second end.
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq)]
#[relationship(relationship_target = ProximalPairsAsB)]
pub struct ProximalEndB(pub Entity);

/// The pairs an entity is the first end of.
#[derive(Component, Debug, Default, PartialEq, Eq)]
#[relationship_target(relationship = ProximalEndA, linked_spawn)]
pub struct ProximalPairsAsA(Vec<Entity>);

/// The pairs an entity is the second end of.
#[derive(Component, Debug, Default, PartialEq, Eq)]
#[relationship_target(relationship = ProximalEndB, linked_spawn)]
pub struct ProximalPairsAsB(Vec<Entity>);

/// The proximal pairs of a world, each as its two ends.
pub type ProximalPairQuery = (&'static ProximalEndA, &'static ProximalEndB);

/// The entities proximal to `entity`, from the pairs `pairs` holds.
pub fn proximal_partners<'a>(
    pairs: impl IntoIterator<Item = (&'a ProximalEndA, &'a ProximalEndB)>,
    entity: Entity,
) -> Vec<Entity> {
    pairs
        .into_iter()
        .filter_map(|(a, b)| {
            if a.0 == entity {
                Some(b.0)
            } else if b.0 == entity {
                Some(a.0)
            } else {
                None
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pair_relates_both_ends_and_goes_with_either() {
        let mut world = World::new();
        let [table, chair, stool] = [(); 3].map(|_| world.spawn_empty().id());
        let first = world.spawn((ProximalEndA(table), ProximalEndB(chair))).id();
        let second = world.spawn((ProximalEndA(stool), ProximalEndB(table))).id();
        let mut pairs = world.query::<ProximalPairQuery>();
        let partners = proximal_partners(pairs.iter(&world), table);
        assert_eq!(partners, vec![chair, stool]);
        assert_eq!(proximal_partners(pairs.iter(&world), chair), vec![table]);
        assert!(world.get::<ProximalPairsAsA>(table).is_some());

        world.despawn(chair);
        assert!(
            world.get_entity(first).is_err(),
            "the pair went with its end"
        );
        assert!(world.get_entity(second).is_ok());
        assert_eq!(proximal_partners(pairs.iter(&world), table), vec![stool]);
    }
}
