//! A stateful sparse Cholesky solver over faer's symbolic/numeric split: the
//! symbolic factorization (ordering, elimination tree, supernodes) is computed once
//! per pattern, and the numeric values and the workspace are reused between
//! refactorizations. The ordering is approximate minimum degree (faer's default).
//! The pattern passed in holds both triangles; faer reads the lower one.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, LltRef, SymbolicCholesky, SymmetricOrdering};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::traits::ComplexField;
use faer::{Conj, MatMut, Par, Side};

/// `L Lᵀ` of a symmetric positive definite matrix with a fixed pattern, in `f64`
/// (or `f32`, for preconditioners: half the memory traffic).
pub struct SparseCholesky<T = f64> {
    symbolic: SymbolicCholesky<usize>,
    values: Vec<T>,
    scratch: MemBuffer,
}

impl<T: ComplexField + Copy> SparseCholesky<T> {
    /// Symbolic factorization of the pattern (lower triangle is read).
    pub fn new(pattern: SymbolicSparseColMatRef<'_, usize>) -> Result<Self, String> {
        let symbolic = factorize_symbolic_cholesky(pattern, Side::Lower, SymmetricOrdering::Amd, Default::default())
            .map_err(|e| format!("symbolic Cholesky: {e:?}"))?;
        let req = symbolic
            .factorize_numeric_llt_scratch::<T>(Par::Seq, Default::default())
            .or(symbolic.solve_in_place_scratch::<T>(1, Par::Seq));
        let scratch = MemBuffer::try_new(req).map_err(|e| format!("{e:?}"))?;
        let values = vec![T::zero_impl(); symbolic.len_val()];
        Ok(SparseCholesky { symbolic, values, scratch })
    }

    /// Number of stored entries of the factor `L`.
    pub fn factor_nnz(&self) -> usize {
        self.symbolic.len_val()
    }

    /// Numeric factorization of the matrix with `values` on the pattern given to `new`.
    pub fn factorize(&mut self, pattern: SymbolicSparseColMatRef<'_, usize>, values: &[T]) -> Result<(), String> {
        let a = SparseColMatRef::new(pattern, values);
        self.symbolic
            .factorize_numeric_llt::<T>(
                &mut self.values,
                a,
                Side::Lower,
                Default::default(),
                Par::Seq,
                MemStack::new(&mut self.scratch),
                Default::default(),
            )
            .map(|_| ())
            .map_err(|e| format!("numeric Cholesky: {e:?}"))
    }

    /// Solve `A x = b` in place (after [`SparseCholesky::factorize`]).
    pub fn solve_in_place(&self, x: &mut [T]) {
        let n = x.len();
        let mut buf = MemBuffer::new(self.symbolic.solve_in_place_scratch::<T>(1, Par::Seq));
        LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(x, n, 1),
            Par::Seq,
            MemStack::new(&mut buf),
        );
    }
}
