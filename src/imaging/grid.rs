//! A regular grid of samples in 2D or 3D.

/// The sample type of the file a grid was decoded from (for reporting; the values
/// are always `f64`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SampleKind {
    U8,
    U16,
    F32,
}

/// Where the samples lie in the space of the file they were read from: sample
/// `(i, j, k)` is at `origin + i axes[0] + j axes[1] + k axes[2]`, in the space
/// named `space` (NRRD's names; a NIfTI file's RAS coordinates are turned into
/// `left-posterior-superior`, as ITK and 3D Slicer read them), or in an unnamed
/// space. A file that gives no placement has unit axes and the origin 0.
#[derive(Debug, Clone, PartialEq)]
pub struct Placement {
    pub axes: [[f64; 3]; 3],
    pub origin: [f64; 3],
    pub space: Option<String>,
}

impl Default for Placement {
    fn default() -> Self {
        Placement::aligned([1.0; 3], [0.0; 3])
    }
}

impl Placement {
    /// Axes along the coordinate axes, `spacing` apart, from `origin`, unnamed.
    pub fn aligned(spacing: [f64; 3], origin: [f64; 3]) -> Placement {
        let mut axes = [[0.0; 3]; 3];
        for a in 0..3 {
            axes[a][a] = spacing[a];
        }
        Placement { axes, origin, space: None }
    }

    /// The distance between neighbouring samples along each axis.
    pub fn spacing(&self) -> [f64; 3] {
        self.axes.map(|v| v.iter().map(|c| c * c).sum::<f64>().sqrt())
    }

    /// The axes as the columns of a matrix.
    pub fn matrix(&self) -> nalgebra::Matrix3<f64> {
        nalgebra::Matrix3::from_fn(|row, col| self.axes[col][row])
    }

    /// A placement given in NIfTI's RAS coordinates, in `left-posterior-superior`
    /// ones (x and y negated), as ITK and 3D Slicer read NIfTI.
    pub fn from_ras(axes: [[f64; 3]; 3], origin: [f64; 3]) -> Placement {
        let lps = |v: [f64; 3]| [-v[0], -v[1], v[2]];
        Placement { axes: axes.map(lps), origin: lps(origin), space: Some("left-posterior-superior".into()) }
    }

    /// The axes and origin in RAS coordinates, from a space that names its
    /// directions (left-posterior-superior, left-anterior-superior,
    /// right-anterior-superior, or their abbreviations); `None` in another space.
    pub fn to_ras(&self) -> Option<([[f64; 3]; 3], [f64; 3])> {
        let flip = match self.space.as_deref()? {
            "left-posterior-superior" | "lps" => [-1.0, -1.0, 1.0],
            "left-anterior-superior" | "las" => [-1.0, 1.0, 1.0],
            "right-anterior-superior" | "ras" => [1.0, 1.0, 1.0],
            _ => return None,
        };
        let turn = |v: [f64; 3]| std::array::from_fn(|c| flip[c] * v[c]);
        Some((self.axes.map(turn), turn(self.origin)))
    }
}

/// Samples on `dims[0] × dims[1] × dims[2]` points, `x` fastest:
/// `values[i + n_x (j + n_y k)]`. A 2D grid has `dims[2] = 1` and `dimension = 2`.
#[derive(Debug, Clone, PartialEq)]
pub struct Grid {
    pub dimension: usize,
    pub dims: [usize; 3],
    pub values: Vec<f64>,
    pub kind: SampleKind,
    /// Where the samples lie in the file's space (written into volume results).
    pub placement: Placement,
    /// How the samples map onto the input's array (its shape and order).
    pub layout: ArrayLayout,
}

/// The input's array as the grid samples it: the input's `dims` along x, y, z;
/// `rows_flipped` when its rows run from the top (a 2D image, the pages of a TIFF
/// stack, a stack of slices) and the grid's from the bottom; `per_input` grid
/// samples per input sample along each axis (more than 1 where a volume was
/// resampled to cubic voxels). Input sample `i` (grid order, after the flip) has its
/// centre at grid coordinate `(i + ½) per_input − ½`.
#[derive(Debug, Clone, PartialEq)]
pub struct ArrayLayout {
    pub dims: [usize; 3],
    pub rows_flipped: bool,
    pub per_input: [f64; 3],
}

impl Grid {
    /// A grid from its parts; `values.len()` must equal the product of `dims`.
    pub fn new(dimension: usize, dims: [usize; 3], values: Vec<f64>, kind: SampleKind) -> Grid {
        assert_eq!(values.len(), dims[0] * dims[1] * dims[2], "grid size");
        assert!(dimension == 3 || dims[2] == 1, "a 2D grid has one slice");
        let layout = ArrayLayout { dims, rows_flipped: dimension == 2, per_input: [1.0; 3] };
        Grid { dimension, dims, values, kind, placement: Placement::default(), layout }
    }

    /// This grid with its rows counted from the bottom where the input's run from
    /// the top (the pages of a TIFF stack, a stack of slices).
    pub fn rows_flipped(mut self) -> Grid {
        self.layout.rows_flipped = true;
        self
    }

    /// The input's array shape, C order: `(rows, columns)` or `(planes, rows, columns)`.
    pub fn array_shape(&self) -> Vec<usize> {
        let d = self.layout.dims;
        if self.dimension == 2 {
            vec![d[1], d[0]]
        } else {
            vec![d[2], d[1], d[0]]
        }
    }

    /// The input's sample spacing along x, y, z (the placement's, times the
    /// resampling's factor).
    pub fn input_spacing(&self) -> [f64; 3] {
        let s = self.placement.spacing();
        std::array::from_fn(|a| s[a] * self.layout.per_input[a])
    }

    /// Grid-order samples (a mask, labels) as an array of the input's shape and
    /// order ([`Grid::array_shape`], C order): each input sample takes the grid
    /// sample nearest its centre, rows from the top where the input's are.
    pub fn to_array<T: Copy>(&self, values: &[T]) -> Vec<T> {
        let ArrayLayout { dims, rows_flipped, per_input } = self.layout;
        let nearest = |a: usize, i: usize| (((i as f64 + 0.5) * per_input[a]) as usize).min(self.dims[a] - 1);
        let xs: Vec<usize> = (0..dims[0]).map(|i| nearest(0, i)).collect();
        let mut out = Vec::with_capacity(dims.iter().product());
        for k in 0..dims[2] {
            let gk = nearest(2, k);
            for r in 0..dims[1] {
                let gj = nearest(1, if rows_flipped { dims[1] - 1 - r } else { r });
                out.extend(xs.iter().map(|&gi| values[self.index(gi, gj, gk)]));
            }
        }
        out
    }

    /// This grid placed at `placement`.
    pub fn placed(self, placement: Placement) -> Grid {
        Grid { placement, ..self }
    }

    /// `L = max(n_x, n_y, n_z)`: one unit of the unit box is `L` samples.
    pub fn scale(&self) -> f64 {
        self.dims.iter().copied().max().unwrap_or(1) as f64
    }

    #[inline]
    pub fn index(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.dims[0] * (j + self.dims[1] * k)
    }

    pub fn len(&self) -> usize {
        self.values.len()
    }

    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// The extent of the grid in the unit box: `(n_x/L, n_y/L, n_z/L)` (2D: `n_z` = 0).
    pub fn extent(&self) -> [f64; 3] {
        let l = self.scale();
        let z = if self.dimension == 2 { 0.0 } else { self.dims[2] as f64 / l };
        [self.dims[0] as f64 / l, self.dims[1] as f64 / l, z]
    }

    /// Values mapped affinely onto `[0, top]` (a constant grid maps to 0). Returns
    /// `None` for a constant grid.
    pub fn normalized(&self, top: f64) -> Option<Grid> {
        let (lo, hi) = self.values.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
        if !(hi > lo) {
            return None;
        }
        let s = top / (hi - lo);
        Some(Grid { values: self.values.iter().map(|v| (v - lo) * s).collect(), ..self.clone() })
    }
}
