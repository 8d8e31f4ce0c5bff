//! The sparsity pattern of P1 matrices on Γ, built once per connectivity.
//!
//! Compressed sparse columns with the full (symmetric) pattern of the one-ring
//! stencil, plus for every element the positions of its `D × D` local entries in the
//! value array, so that assembly only refills values.

use faer::sparse::SymbolicSparseColMat;

/// One-ring CSC pattern plus element-to-value scatter positions.
#[derive(Debug, Clone)]
pub struct Pattern<const D: usize> {
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// `slots[e][a][b]`: index in the value array of entry `(el[a], el[b])`.
    slots: Vec<[[usize; D]; D]>,
    /// Position of the diagonal entry of every column.
    diag: Vec<usize>,
    symbolic: SymbolicSparseColMat<usize>,
}

impl<const D: usize> Pattern<D> {
    /// Pattern of `n × n` matrices assembled over `elements`.
    pub fn new(n: usize, elements: &[[usize; D]]) -> Self {
        // every column in one flat array: its diagonal and the other vertices of its
        // elements (with repeats), then sorted and deduplicated column by column
        let mut start = vec![1usize; n + 1];
        start[n] = 0;
        for el in elements {
            for &v in el {
                start[v] += D - 1;
            }
        }
        let mut total = 0;
        for s in start.iter_mut() {
            (*s, total) = (total, total + *s);
        }
        let mut raw = vec![0usize; total];
        let mut fill = start[..n].to_vec();
        for (i, f) in fill.iter_mut().enumerate() {
            raw[*f] = i;
            *f += 1;
        }
        for el in elements {
            for b in 0..D {
                for a in 0..D {
                    if a != b {
                        raw[fill[el[b]]] = el[a];
                        fill[el[b]] += 1;
                    }
                }
            }
        }
        let (mut col_ptr, mut row_idx) = (Vec::with_capacity(n + 1), Vec::with_capacity(total));
        col_ptr.push(0);
        for j in 0..n {
            let c = &mut raw[start[j]..start[j + 1]];
            c.sort_unstable();
            let mut last = usize::MAX;
            for &r in c.iter() {
                if r != last {
                    row_idx.push(r);
                    last = r;
                }
            }
            col_ptr.push(row_idx.len());
        }
        let find = |row: usize, col: usize| -> usize {
            let range = &row_idx[col_ptr[col]..col_ptr[col + 1]];
            col_ptr[col] + range.binary_search(&row).expect("entry in pattern")
        };
        let slots =
            elements.iter().map(|el| std::array::from_fn(|a| std::array::from_fn(|b| find(el[a], el[b])))).collect();
        let diag = (0..n).map(|i| find(i, i)).collect();
        let symbolic = SymbolicSparseColMat::new_checked(n, n, col_ptr.clone(), None, row_idx.clone());
        Pattern { n, col_ptr, row_idx, slots, diag, symbolic }
    }

    pub fn size(&self) -> usize {
        self.n
    }
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }
    pub fn col_ptr(&self) -> &[usize] {
        &self.col_ptr
    }
    pub fn row_idx(&self) -> &[usize] {
        &self.row_idx
    }
    pub fn slots(&self) -> &[[[usize; D]; D]] {
        &self.slots
    }
    pub fn diag(&self) -> &[usize] {
        &self.diag
    }
    pub fn symbolic(&self) -> &SymbolicSparseColMat<usize> {
        &self.symbolic
    }

    /// Adds element `e`'s local matrix, `local(a, b)` for its vertices `a, b`, to the
    /// values `a` of the global matrix on this pattern (the scatter of every global
    /// assembly).
    #[inline]
    pub fn add_local(&self, a: &mut [f64], e: usize, local: impl Fn(usize, usize) -> f64) {
        let slots = &self.slots[e];
        for (i, row) in slots.iter().enumerate() {
            for (j, &s) in row.iter().enumerate() {
                a[s] += local(i, j);
            }
        }
    }

    /// `y = A x` for values `a` on this pattern.
    pub fn mul(&self, a: &[f64], x: &[f64], y: &mut [f64]) {
        csc_mul(&self.col_ptr, &self.row_idx, a, x, y);
    }

    /// The pattern of `A·A` (two-ring stencil) in CSC form: `(col_ptr, row_idx)`.
    pub fn squared(&self) -> (Vec<usize>, Vec<usize>) {
        let mut mark = vec![usize::MAX; self.n];
        let mut cols: Vec<Vec<usize>> = Vec::with_capacity(self.n);
        for k in 0..self.n {
            let mut c = Vec::new();
            for p in self.col_ptr[k]..self.col_ptr[k + 1] {
                let j = self.row_idx[p];
                for q in self.col_ptr[j]..self.col_ptr[j + 1] {
                    let i = self.row_idx[q];
                    if mark[i] != k {
                        mark[i] = k;
                        c.push(i);
                    }
                }
            }
            cols.push(c);
        }
        compress(cols)
    }
}

/// `y = A x` for a CSC matrix `(col_ptr, row_idx, values)`.
pub fn csc_mul(col_ptr: &[usize], row_idx: &[usize], values: &[f64], x: &[f64], y: &mut [f64]) {
    y.iter_mut().for_each(|v| *v = 0.0);
    for (j, &xj) in x.iter().enumerate() {
        for k in col_ptr[j]..col_ptr[j + 1] {
            y[row_idx[k]] += values[k] * xj;
        }
    }
}

/// Sort and deduplicate column lists into CSC arrays.
pub(crate) fn compress(mut cols: Vec<Vec<usize>>) -> (Vec<usize>, Vec<usize>) {
    let mut col_ptr = Vec::with_capacity(cols.len() + 1);
    col_ptr.push(0);
    let mut row_idx = Vec::new();
    for c in &mut cols {
        c.sort_unstable();
        c.dedup();
        row_idx.extend_from_slice(c);
        col_ptr.push(row_idx.len());
    }
    (col_ptr, row_idx)
}
