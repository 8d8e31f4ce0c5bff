//! Groups: disk patches glued into larger disks, level by level over blocks of
//! `2ʲ × 2ʲ × 2ʲ` cells. At level `j` the disks of level `j − 1` (a disk patch at
//! level 0) of one block and one class of normals are glued one to the next
//! while each shares exactly one arc of boundary with the disk built so far and
//! no other vertex: gluing two disks along one arc gives a disk, whose boundary
//! loop is kept. A group whose patches are all proved embedded over one plane
//! with one orientation is embedded as a whole when its loop projects simple (the
//! degree argument of the patches): no pair of its patches needs a test.

/// A group: its patches, its boundary loop (vertices in order), and its level
/// (an index of [`Groups::of`]).
#[derive(Debug, Clone)]
pub(super) struct Group {
    pub patches: Vec<u32>,
    pub boundary: Vec<usize>,
    pub level: usize,
}

/// The groups of all levels, and the group of each patch at each level
/// (`u32::MAX` where the patch is in none of that level).
#[derive(Debug, Clone, Default)]
pub(super) struct Groups {
    pub groups: Vec<Group>,
    pub of: Vec<Vec<u32>>,
}

/// The levels of blocks (of up to `2⁸` cells a side), before the last.
const LEVELS: usize = 8;

impl Groups {
    /// The groups of patches with boundary loops `loops` (`None`: not a disk),
    /// grid cells and classes `cells`, over `vertices` vertices; `across(u, v)`
    /// is the patch across the boundary edge `u → v`.
    pub fn new(
        loops: &[Option<&Vec<usize>>],
        cells: &[[i64; 4]],
        vertices: usize,
        across: impl Fn(usize, usize) -> u32,
    ) -> Groups {
        let n = loops.len();
        // the disks of the level below: patches, loop
        let mut units: Vec<(Vec<u32>, Vec<usize>)> =
            (0..n).filter_map(|q| loops[q].map(|lp| (vec![q as u32], lp.clone()))).collect();
        let (mut groups, mut of) = (Vec::new(), Vec::new());
        let (mut at, mut stamp) = (vec![(u32::MAX, 0u32); vertices], 0u32);
        // the last level's block is the whole grid: an octree's blocks are split
        // by the same planes at every level
        for level in 1..=LEVELS + 1 {
            let mut unit_of = vec![u32::MAX; n];
            for (u, (patches, _)) in units.iter().enumerate() {
                patches.iter().for_each(|&q| unit_of[q as usize] = u as u32);
            }
            let block = |u: usize| {
                let c = cells[units[u].0[0] as usize];
                match level > LEVELS {
                    true => [0, 0, 0, c[3]],
                    false => [c[0] >> level, c[1] >> level, c[2] >> level, c[3]],
                }
            };
            let mut taken = vec![false; units.len()];
            let (mut next, mut level_of) = (Vec::new(), vec![u32::MAX; n]);
            for u in 0..units.len() {
                if taken[u] {
                    continue;
                }
                taken[u] = true;
                let (mut patches, mut lp) = units[u].clone();
                let mut grown = true;
                while grown {
                    grown = false;
                    let mut candidates: Vec<u32> = (0..lp.len())
                        .map(|i| across(lp[i], lp[(i + 1) % lp.len()]))
                        .filter_map(|q| unit_of.get(q as usize).copied())
                        .filter(|&h| h != u32::MAX && !taken[h as usize] && block(h as usize) == block(u))
                        .collect();
                    candidates.sort_unstable();
                    candidates.dedup();
                    for h in candidates {
                        stamp += 1;
                        if let Some(glued) = glue(&lp, &units[h as usize].1, &mut at, stamp) {
                            (lp, grown, taken[h as usize]) = (glued, true, true);
                            patches.extend_from_slice(&units[h as usize].0);
                        }
                    }
                }
                if patches.len() > units[u].0.len() {
                    let id = groups.len() as u32;
                    patches.iter().for_each(|&q| level_of[q as usize] = id);
                    groups.push(Group { patches: patches.clone(), boundary: lp.clone(), level: of.len() });
                }
                next.push((patches, lp));
            }
            if next.len() < units.len() {
                of.push(level_of);
            }
            units = next;
        }
        Groups { groups, of }
    }

    /// Which groups are proved embedded by `proved`, tried from the top level
    /// down: a group inside one already proved is not tried (nor counted), its
    /// pairs being in that one.
    pub fn certify(&self, proved: impl Fn(&Group) -> bool) -> Vec<bool> {
        let mut certified = vec![false; self.groups.len()];
        for g in (0..self.groups.len()).rev() {
            let group = &self.groups[g];
            let q = group.patches[0] as usize;
            let inside = self.of[group.level + 1..].iter().any(|of| of[q] != u32::MAX && certified[of[q] as usize]);
            certified[g] = !inside && proved(group);
        }
        certified
    }

    /// Whether patches `a` and `b` are in one group that `certified` holds.
    pub fn together(&self, a: usize, b: usize, certified: &[bool]) -> bool {
        self.of.iter().any(|of| of[a] != u32::MAX && of[a] == of[b] && certified[of[a] as usize])
    }
}

/// The loop of the disks with loops `g` and `h` glued, when they share exactly
/// one arc (a run of edges of `h` whose reverses are edges of `g`) and no other
/// vertex; `at` is scratch by vertex (stamp, position in `g`).
fn glue(g: &[usize], h: &[usize], at: &mut [(u32, u32)], stamp: u32) -> Option<Vec<usize>> {
    let (ng, nh) = (g.len(), h.len());
    for (i, &v) in g.iter().enumerate() {
        at[v] = (stamp, i as u32);
    }
    let pos = |v: usize, at: &[(u32, u32)]| (at[v].0 == stamp).then_some(at[v].1 as usize);
    // h's edge i (h[i] → h[i + 1]) is shared when g has h[i + 1] → h[i]
    let shared = |i: usize, at: &[(u32, u32)]| pos(h[(i + 1) % nh], at).is_some_and(|p| g[(p + 1) % ng] == h[i]);
    let flags: Vec<bool> = (0..nh).map(|i| shared(i, at)).collect();
    let starts: Vec<usize> = (0..nh).filter(|&i| flags[i] && !flags[(i + nh - 1) % nh]).collect();
    let [s] = starts[..] else { return None };
    let m = (s..s + nh).take_while(|&i| flags[i % nh]).count();
    if m >= nh || m >= ng {
        return None;
    }
    // no vertex of h off the arc on g
    if (m + 1..nh).any(|i| pos(h[(s + i) % nh], at).is_some()) {
        return None;
    }
    // g from the arc's start (h[s]) round to its end (h[s + m]), then h on
    let t = pos(h[s], at)?;
    let mut lp: Vec<usize> = (0..=ng - m).map(|i| g[(t + i) % ng]).collect();
    lp.extend((m + 1..nh).map(|i| h[(s + i) % nh]));
    Some(lp)
}
