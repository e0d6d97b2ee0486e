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
