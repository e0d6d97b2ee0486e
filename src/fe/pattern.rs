//! The sparsity pattern of an assembled tangent, built once from the
//! elements' connectivity: a dof couples with every dof of every node that
//! shares an element with its node (the nodal blocks of the element
//! matrices). Contact pairs, follower couples and follower pressures add
//! entries only inside such blocks, so the pattern holds every tangent of a
//! model whatever its contact set.
//!
//! The pattern keeps the entries that vanish at a particular state (at
//! lambda = 0 on a flat strip half of them do: membrane and bending
//! decouple), because they fill as soon as the shell bends, and a fixed
//! pattern keeps one symbolic analysis for the whole run.

use crate::linalg::Structure;

use super::dof::PER_NODE;

/// The compressed-column pattern of the free dofs (`free[global]` = the
/// free index, numbered in increasing global order) coupled through
/// `elements` (lists of node indices).
pub fn node_block_structure<'a>(
    n_nodes: usize,
    elements: impl Iterator<Item = &'a [usize]>,
    free: &[Option<usize>],
    n_free: usize,
) -> Structure {
    let mut neighbours: Vec<Vec<usize>> = vec![vec![]; n_nodes];
    for nodes in elements {
        for &a in nodes {
            neighbours[a].extend_from_slice(nodes);
        }
    }
    for list in &mut neighbours {
        list.sort_unstable();
        list.dedup();
    }
    let mut col_ptr = Vec::with_capacity(n_free + 1);
    col_ptr.push(0);
    let mut row_idx = Vec::new();
    for (node, list) in neighbours.iter().enumerate() {
        for k in 0..PER_NODE {
            if free[node * PER_NODE + k].is_none() {
                continue;
            }
            // Free indices grow with the global index: rows come out sorted.
            for &m in list {
                row_idx.extend((0..PER_NODE).filter_map(|l| free[m * PER_NODE + l]));
            }
            col_ptr.push(row_idx.len());
        }
    }
    debug_assert_eq!(col_ptr.len(), n_free + 1);
    Structure::from_compressed(n_free, col_ptr, row_idx)
        .expect("rows of a node-block pattern are sorted")
}

/// Where an element matrix goes in a node-block pattern, so that the
/// assembly adds without searching: `[b][a]` is, for the element's local
/// column b (node b / 6, dof b % 6), the slot of node a's first free row
/// in that dof's column; node a's other free rows follow it (the pattern
/// lists a node's rows together). [`NO_SLOT`] where the column's dof is
/// fixed or node a has no free dof.
pub type ElementSlots = [[u32; 4]; 4 * PER_NODE];
pub const NO_SLOT: u32 = u32::MAX;

/// The [`ElementSlots`] of the 4-node element `nodes` in `structure` (built
/// by [`node_block_structure`] from the same `free`); `None` if a slot does
/// not fit 32 bits (then the assembly searches).
pub fn element_slots(
    structure: &Structure,
    nodes: &[usize; 4],
    free: &[Option<usize>],
) -> Option<ElementSlots> {
    let mut slots = [[NO_SLOT; 4]; 4 * PER_NODE];
    for (b, column) in slots.iter_mut().enumerate() {
        let Some(j) = free[nodes[b / PER_NODE] * PER_NODE + b % PER_NODE] else {
            continue;
        };
        for (a, &node) in nodes.iter().enumerate() {
            let Some(first) = (0..PER_NODE).find_map(|l| free[node * PER_NODE + l]) else {
                continue;
            };
            let slot = structure.slot(first, j)?;
            column[a] = u32::try_from(slot).ok().filter(|&s| s != NO_SLOT)?;
        }
    }
    Some(slots)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two elements sharing an edge, one dof fixed: every slot holds its
    /// node's free rows in order.
    #[test]
    fn element_slots_point_at_each_nodes_rows() {
        let elements = [[0usize, 1, 2, 3], [1, 4, 5, 2]];
        let n_nodes = 6;
        let mut free = vec![None; n_nodes * PER_NODE];
        let mut next = 0;
        for (g, f) in free.iter_mut().enumerate() {
            if g != 2 * PER_NODE + 1 {
                *f = Some(next);
                next += 1;
            }
        }
        let s = node_block_structure(n_nodes, elements.iter().map(|e| &e[..]), &free, next);
        for nodes in &elements {
            let slots = element_slots(&s, nodes, &free).expect("small pattern");
            for (b, column) in slots.iter().enumerate() {
                let col = free[nodes[b / PER_NODE] * PER_NODE + b % PER_NODE];
                for (a, &node) in nodes.iter().enumerate() {
                    let rows: Vec<usize> = (0..PER_NODE)
                        .filter_map(|l| free[node * PER_NODE + l])
                        .collect();
                    match col {
                        None => assert_eq!(column[a], NO_SLOT),
                        Some(j) => {
                            for (m, &r) in rows.iter().enumerate() {
                                assert_eq!(s.slot(r, j), Some(column[a] as usize + m));
                            }
                        }
                    }
                }
            }
        }
    }
}
