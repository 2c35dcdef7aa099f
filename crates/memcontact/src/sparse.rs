//! Sparse symmetric matrices in compressed-row form with a shared pattern, and a sparse
//! Cholesky factorisation (faer) that keeps its symbolic analysis between refactorisations.

use crate::error::{Error, Result};
use rayon::prelude::*;
use std::sync::Arc;

/// Below this many rows, matrix-vector products run serially (threads cost more).
const PAR_ROWS: usize = 20_000;
/// Stored entries from which a product runs in parallel whatever the number of rows.
const PAR_ENTRIES: usize = 1 << 16;

/// A sparsity pattern: sorted column indices per row. Shared by S, L and the Newton
/// matrices, so that it is built once (assemble once, keep the pattern).
#[derive(Debug, Clone, PartialEq)]
pub struct Pattern {
    /// Row `i` occupies `col[row_ptr[i]..row_ptr[i + 1]]` ([`Pattern::ptr`]). Four bytes
    /// per row: a pattern holds fewer than 2³² entries ([`MAX_ENTRIES`]).
    pub row_ptr: Vec<u32>,
    /// Column indices, sorted within each row.
    pub col: Vec<u32>,
}

/// The most entries a [`Pattern`] holds (its row pointers are `u32`): about 600 million
/// unknowns of a triangle mesh, far beyond what a run agrees to allocate
/// ([`crate::limits`]).
pub const MAX_ENTRIES: usize = u32::MAX as usize;

impl Pattern {
    /// Where row `i` starts in `col` (and where row `i − 1` ends).
    #[inline(always)]
    pub fn ptr(&self, i: usize) -> usize {
        self.row_ptr[i] as usize
    }

    /// The columns of row `i`.
    #[inline(always)]
    pub fn cols(&self, i: usize) -> &[u32] {
        &self.col[self.ptr(i)..self.ptr(i + 1)]
    }

    /// Number of rows (= columns: the patterns here are square).
    pub fn n(&self) -> usize {
        self.row_ptr.len() - 1
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.col.len()
    }

    /// The position of entry `(i, j)` in the value array, if stored.
    pub fn find(&self, i: usize, j: usize) -> Option<usize> {
        let row = &self.col[self.ptr(i)..self.ptr(i + 1)];
        row.binary_search(&(j as u32)).ok().map(|k| self.ptr(i) + k)
    }

    /// The pattern of consecutive blocks of rows, each given as its rows' lengths and their
    /// columns concatenated. The blocks are put into place on all threads: the arrays are
    /// large and fresh, and their first touch is shared by the threads.
    ///
    /// # Panics
    /// With more than [`MAX_ENTRIES`] entries (callers check the counts of large patterns
    /// first and report an error).
    pub fn from_blocks(blocks: &[(Vec<u32>, Vec<u32>)]) -> Pattern {
        let n: usize = blocks.iter().map(|(lengths, _)| lengths.len()).sum();
        let nnz: usize = blocks.iter().map(|(_, c)| c.len()).sum();
        assert!(
            nnz <= MAX_ENTRIES,
            "a sparsity pattern of {nnz} entries, more than {MAX_ENTRIES}"
        );
        let mut row_ptr = filled(n + 1, 0u32);
        let mut col = filled(nnz, 0u32);
        let mut pieces = Vec::with_capacity(blocks.len());
        let (mut ptr_rest, mut col_rest) = (&mut row_ptr[1..], &mut col[..]);
        let mut start = 0;
        for (lengths, cols) in blocks {
            let (p, pr) = ptr_rest.split_at_mut(lengths.len());
            let (c, cr) = col_rest.split_at_mut(cols.len());
            pieces.push((start, lengths, cols, p, c));
            (ptr_rest, col_rest) = (pr, cr);
            start += cols.len();
        }
        pieces
            .into_par_iter()
            .for_each(|(start, lengths, cols, p, c)| {
                let mut end = start as u32;
                for (slot, &l) in p.iter_mut().zip(lengths) {
                    end += l;
                    *slot = end;
                }
                c.copy_from_slice(cols);
            });
        Pattern { row_ptr, col }
    }

    /// The position of every diagonal entry (all must be stored).
    pub fn diagonal_positions(&self) -> Vec<usize> {
        map_rows(self.n(), |i| {
            self.find(i, i).expect("the pattern stores the diagonal")
        })
    }
}

/// A square sparse matrix in compressed-row form over a shared [`Pattern`].
#[derive(Debug, Clone)]
pub struct Csr {
    /// The sparsity pattern.
    pub pattern: Arc<Pattern>,
    /// One value per pattern entry.
    pub val: Vec<f64>,
}

impl Csr {
    /// A matrix of zeros on `pattern`.
    pub fn zeros(pattern: Arc<Pattern>) -> Csr {
        let nnz = pattern.nnz();
        Csr {
            pattern,
            val: zeroed(nnz),
        }
    }

    /// A diagonal matrix stored on its own diagonal pattern.
    pub fn diagonal(d: &[f64]) -> Csr {
        Csr {
            pattern: Arc::new(Pattern {
                row_ptr: (0..=d.len() as u32).collect(),
                col: (0..d.len() as u32).collect(),
            }),
            val: d.to_vec(),
        }
    }

    /// Builds a matrix from `(row, col, value)` triplets (duplicates summed). Meant for
    /// small matrices (coarse levels, tests).
    pub fn from_triplets(n: usize, triplets: &[(usize, usize, f64)]) -> Csr {
        let mut rows: Vec<Vec<(u32, f64)>> = vec![Vec::new(); n];
        for &(i, j, v) in triplets {
            rows[i].push((j as u32, v));
        }
        let mut row_ptr = vec![0u32];
        let mut col = Vec::new();
        let mut val = Vec::new();
        for mut r in rows {
            r.sort_unstable_by_key(|e| e.0);
            let mut k = 0;
            while k < r.len() {
                let (j, mut v) = r[k];
                k += 1;
                while k < r.len() && r[k].0 == j {
                    v += r[k].1;
                    k += 1;
                }
                col.push(j);
                val.push(v);
            }
            row_ptr.push(u32::try_from(col.len()).expect("a small matrix"));
        }
        Csr {
            pattern: Arc::new(Pattern { row_ptr, col }),
            val,
        }
    }

    /// Number of rows.
    pub fn n(&self) -> usize {
        self.pattern.n()
    }

    /// Entry `(i, j)` (zero when not stored).
    pub fn get(&self, i: usize, j: usize) -> f64 {
        self.pattern.find(i, j).map_or(0.0, |k| self.val[k])
    }

    /// The diagonal.
    pub fn diag(&self) -> Vec<f64> {
        map_rows(self.n(), |i| self.get(i, i))
    }

    /// Row `i` as (columns, values).
    #[inline]
    pub fn row(&self, i: usize) -> (&[u32], &[f64]) {
        let r = self.pattern.ptr(i)..self.pattern.ptr(i + 1);
        (&self.pattern.col[r.clone()], &self.val[r])
    }

    /// `(A x)_i`.
    #[inline]
    pub fn row_dot(&self, i: usize, x: &[f64]) -> f64 {
        let (c, v) = self.row(i);
        c.iter().zip(v).map(|(&j, &a)| a * x[j as usize]).sum()
    }

    /// `y = A x` (parallel for large matrices; the result does not depend on the thread
    /// count because every row is summed in the same order).
    pub fn mul_into(&self, x: &[f64], y: &mut [f64]) {
        // Split by work: the coarse levels of an algebraic hierarchy have few rows but
        // long ones.
        if self.n() >= PAR_ROWS || self.val.len() >= PAR_ENTRIES {
            y.par_iter_mut()
                .enumerate()
                .with_min_len(4096)
                .for_each(|(i, yi)| *yi = self.row_dot(i, x));
        } else {
            for (i, yi) in y.iter_mut().enumerate() {
                *yi = self.row_dot(i, x);
            }
        }
    }

    /// `A x` as a new vector.
    pub fn mul(&self, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; self.n()];
        self.mul_into(x, &mut y);
        y
    }

    /// `xᵀ A x`, summed over fixed blocks of rows in block order (the same result for any
    /// number of threads).
    pub fn quad_form(&self, x: &[f64]) -> f64 {
        sum_blocks(self.n(), |r| {
            r.map(|i| x[i] * self.row_dot(i, x)).sum::<f64>()
        })
    }

    /// `true` when every entry is finite.
    pub fn is_finite(&self) -> bool {
        first_non_finite(&self.val).is_none()
    }
}

/// A sparse LLᵀ factorisation of a symmetric positive definite [`Csr`] (faer's supernodal
/// Cholesky with AMD ordering). The symbolic analysis is done once per pattern;
/// [`Cholesky::refactor`] redoes only the numeric part, as an active-set loop needs.
pub struct Cholesky {
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    symbolic: faer::sparse::linalg::solvers::SymbolicLlt<usize>,
    numeric: Option<faer::sparse::linalg::solvers::Llt<usize, f64>>,
}

impl Cholesky {
    /// Analyses the pattern of `a` and factorises it.
    pub fn new(a: &Csr) -> Result<Cholesky> {
        use faer::sparse::SymbolicSparseColMatRef;
        let n = a.n();
        // A symmetric matrix in CSR is its own CSC: row pointers become column pointers.
        let col_ptr: Vec<usize> = a.pattern.row_ptr.iter().map(|&p| p as usize).collect();
        let row_idx: Vec<usize> = a.pattern.col.iter().map(|&j| j as usize).collect();
        let sym = SymbolicSparseColMatRef::new_checked(n, n, &col_ptr, None, &row_idx);
        let symbolic = faer::sparse::linalg::solvers::SymbolicLlt::try_new(sym, faer::Side::Lower)
            .map_err(|e| Error::Solver {
                solver: "cholesky".into(),
                message: format!("symbolic analysis failed: {e:?}"),
            })?;
        let mut c = Cholesky {
            n,
            col_ptr,
            row_idx,
            symbolic,
            numeric: None,
        };
        c.refactor(a)?;
        Ok(c)
    }

    /// Factorises new values on the same pattern.
    pub fn refactor(&mut self, a: &Csr) -> Result<()> {
        use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
        debug_assert_eq!(a.n(), self.n);
        if !a.is_finite() {
            return Err(Error::Solver {
                solver: "cholesky".into(),
                message: "the matrix has non-finite entries".into(),
            });
        }
        let sym = SymbolicSparseColMatRef::new_checked(
            self.n,
            self.n,
            &self.col_ptr,
            None,
            &self.row_idx,
        );
        let mat = SparseColMatRef::new(sym, &a.val);
        let llt = faer::sparse::linalg::solvers::Llt::try_new_with_symbolic(
            self.symbolic.clone(),
            mat,
            faer::Side::Lower,
        )
        .map_err(|e| Error::Solver {
            solver: "cholesky".into(),
            message: format!("the matrix is not positive definite ({e:?})"),
        })?;
        self.numeric = Some(llt);
        Ok(())
    }

    /// Solves `A x = b` in place.
    pub fn solve_in_place(&self, b: &mut [f64]) {
        use faer::linalg::solvers::Solve;
        let llt = self.numeric.as_ref().expect("factorised in new()");
        let rhs = faer::MatMut::from_column_major_slice_mut(b, self.n, 1);
        llt.solve_in_place(rhs);
    }
}

/// Indices per block of the fixed-block reductions ([`map_blocks`]).
pub(crate) const REDUCE_BLOCK: usize = 4096;

/// `f` on the ranges of [`REDUCE_BLOCK`] consecutive indices that cover `0..n` (in parallel
/// for long ranges), the results in block order: a sum of them rounds the same for any
/// number of threads.
pub(crate) fn map_blocks<T: Send>(
    n: usize,
    f: impl Fn(std::ops::Range<usize>) -> T + Sync + Send,
) -> Vec<T> {
    let block = |b: usize| f(block_range(b, n));
    let blocks = n.div_ceil(REDUCE_BLOCK);
    if n >= PAR_ROWS {
        (0..blocks).into_par_iter().map(block).collect()
    } else {
        (0..blocks).map(block).collect()
    }
}

/// `n` zeros written out (on all threads for long vectors), for arrays whose first use
/// reads them (`+=` in assembly, Galerkin products). The allocator hands out fresh pages
/// that are zero without being touched; the first read would then map the kernel's shared
/// zero page and the first write replace it, a second fault that also flushes the other
/// cores' TLBs. Written first, each page faults once, as a write, on whichever core
/// writes it.
pub fn zeroed(n: usize) -> Vec<f64> {
    filled(n, 0.0)
}

/// `n` copies of `value` written out, on all threads for long vectors. For the large
/// arrays of the solver's setup: `vec![value; n]` fills on one thread (or, for zeros, on
/// memory the allocator reuses), and on fresh memory that fill is mostly page faults,
/// which cost as much as the arithmetic of an iteration and share out over the cores.
pub fn filled<T: Copy + Send + Sync>(n: usize, value: T) -> Vec<T> {
    // From uninitialised capacity, so that the writes cannot be elided as redundant.
    let mut v = Vec::with_capacity(n);
    if n >= PAR_ROWS {
        v.par_extend(rayon::iter::repeat_n(value, n).with_min_len(REDUCE_BLOCK));
    } else {
        v.resize(n, value);
    }
    v
}

/// Block `b` of [`REDUCE_BLOCK`] indices of `0..n`.
fn block_range(b: usize, n: usize) -> std::ops::Range<usize> {
    b * REDUCE_BLOCK..((b + 1) * REDUCE_BLOCK).min(n)
}

/// `f(i)` for every row `i < n`, on all threads for many rows.
fn map_rows<T: Send>(n: usize, f: impl Fn(usize) -> T + Sync + Send) -> Vec<T> {
    if n >= PAR_ROWS {
        (0..n).into_par_iter().with_min_len(4096).map(f).collect()
    } else {
        (0..n).map(f).collect()
    }
}

/// The sum of `f` over the blocks of [`map_blocks`], added in block order (the same for
/// any number of threads; short ranges are summed on the calling thread, without
/// allocating).
pub(crate) fn sum_blocks(n: usize, f: impl Fn(std::ops::Range<usize>) -> f64 + Sync + Send) -> f64 {
    if n >= PAR_ROWS {
        map_blocks(n, f).iter().sum()
    } else {
        (0..n.div_ceil(REDUCE_BLOCK))
            .map(|b| f(block_range(b, n)))
            .sum()
    }
}

/// Euclidean dot product, summed in fixed blocks ([`sum_blocks`]: the same result for any
/// number of threads).
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    sum_blocks(a.len().min(b.len()), |r| {
        a[r.clone()]
            .iter()
            .zip(&b[r])
            .map(|(x, y)| x * y)
            .sum::<f64>()
    })
}

/// Maximum norm.
pub fn norm_inf(a: &[f64]) -> f64 {
    let parts = map_blocks(a.len(), |r| {
        a[r].iter().fold(0.0, |m: f64, x| m.max(x.abs()))
    });
    parts.into_iter().fold(0.0, f64::max)
}

/// The first index of `x` that holds a value that is not finite (on all threads for long
/// vectors), for the data and result checks.
pub fn first_non_finite(x: &[f64]) -> Option<usize> {
    first_where(x, |v| !v.is_finite())
}

/// The first index `i` with `bad(x[i])`, on all threads for long slices. Each block of
/// [`REDUCE_BLOCK`] items is tested without a branch per item (with a branch-free `bad`,
/// the test vectorises); the index is then looked for in the first block that fails. For
/// the checks of input and results, which nearly always find nothing.
pub fn first_where<T: Copy + Sync>(
    x: &[T],
    bad: impl Fn(T) -> bool + Sync + Send,
) -> Option<usize> {
    let failed = map_blocks(x.len(), |r| x[r].iter().fold(false, |f, &v| f | bad(v)));
    let b = failed.iter().position(|&f| f)?;
    let r = block_range(b, x.len());
    x[r.clone()]
        .iter()
        .position(|&v| bad(v))
        .map(|i| r.start + i)
}

/// Groups the entries of items `0..m` by key, in compressed-row form: `entries(i)` gives
/// item i's up to `K` entries `(key, value)` (those with `key ≥ n_keys` are left out), and
/// the result `(ptr, values)` holds the values of key `k` in `values[ptr[k]..ptr[k + 1]]`,
/// in increasing item order (a stable counting sort). Large inputs whose keys follow the
/// items' order (a mesh numbered for locality) are split into ranges of keys, one per
/// thread ([`group_by_key_by_ranges`]). Scattered keys (a mesh in a mesh generator's
/// numbering), whose counters would miss the cache at every entry, are sorted in two
/// passes that stay in cache: fixed chunks of items are first sorted by buckets of
/// [`KEY_BUCKET`] consecutive keys, then every bucket gathers its entries from the chunks
/// in order and sorts them by key. Either way the result is the same, for any number of
/// threads.
pub(crate) fn group_by_key<T, const K: usize>(
    n_keys: usize,
    m: usize,
    entries: impl Fn(usize) -> [Option<(u32, T)>; K] + Sync,
) -> (Vec<usize>, Vec<T>)
where
    T: Copy + Default + Send + Sync,
{
    if n_keys < PARALLEL_KEYS || keys_follow_items(n_keys, m, &entries) {
        group_by_key_by_ranges(n_keys, m, entries)
    } else {
        group_by_key_in_buckets(n_keys, m, entries)
    }
}

/// [`group_by_key`] for scattered keys: chunks of items sorted by buckets of
/// [`KEY_BUCKET`] keys, then every bucket sorted by key.
fn group_by_key_in_buckets<T, const K: usize>(
    n_keys: usize,
    m: usize,
    entries: impl Fn(usize) -> [Option<(u32, T)>; K] + Sync,
) -> (Vec<usize>, Vec<T>)
where
    T: Copy + Default + Send + Sync,
{
    // Items per chunk of the first pass: at least 2¹⁴, at most 256 chunks (each keeps a
    // counter per bucket).
    let chunk = (1 << 14).max(m.div_ceil(256));
    let n_buckets = n_keys.div_ceil(KEY_BUCKET);
    let bucket_of = |key: u32| key as usize / KEY_BUCKET;
    // First pass: each chunk's entries sorted by bucket (in item order within a bucket),
    // with where each bucket starts in it.
    let chunks: Vec<BucketedChunk<T>> = (0..m.div_ceil(chunk))
        .into_par_iter()
        .map(|c| {
            let items = c * chunk..((c + 1) * chunk).min(m);
            let mut start = vec![0usize; n_buckets + 1];
            let owned = |i: usize| {
                entries(i)
                    .into_iter()
                    .flatten()
                    .filter(|&(key, _)| (key as usize) < n_keys)
            };
            for i in items.clone() {
                for (key, _) in owned(i) {
                    start[bucket_of(key) + 1] += 1;
                }
            }
            for b in 0..n_buckets {
                start[b + 1] += start[b];
            }
            let mut next = start.clone();
            let mut sorted = vec![(0u32, T::default()); start[n_buckets]];
            for i in items {
                for (key, value) in owned(i) {
                    let b = bucket_of(key);
                    sorted[next[b]] = (key, value);
                    next[b] += 1;
                }
            }
            (start, sorted)
        })
        .collect();
    // Where every bucket's values start in the result.
    let mut bucket_start = vec![0usize; n_buckets + 1];
    for b in 0..n_buckets {
        let len: usize = chunks
            .iter()
            .map(|(start, _)| start[b + 1] - start[b])
            .sum();
        bucket_start[b + 1] = bucket_start[b] + len;
    }
    let mut ptr = filled(n_keys + 1, 0usize);
    let mut values = filled(bucket_start[n_buckets], T::default());
    // Second pass: every bucket sorts its entries by key, into its own parts of `ptr` and
    // `values`.
    let mut parts = Vec::with_capacity(n_buckets);
    let (mut ptr_rest, mut val_rest) = (&mut ptr[1..], &mut values[..]);
    for b in 0..n_buckets {
        let keys = (n_keys - b * KEY_BUCKET).min(KEY_BUCKET);
        let (p, pr) = ptr_rest.split_at_mut(keys);
        let (v, vr) = val_rest.split_at_mut(bucket_start[b + 1] - bucket_start[b]);
        parts.push((b, p, v));
        (ptr_rest, val_rest) = (pr, vr);
    }
    let chunks = &chunks;
    let bucket_start = &bucket_start;
    parts.into_par_iter().for_each(|(b, ptr_part, out)| {
        let lo = (b * KEY_BUCKET) as u32;
        let own = || {
            chunks
                .iter()
                .flat_map(move |(start, sorted)| &sorted[start[b]..start[b + 1]])
        };
        let mut next = vec![0usize; ptr_part.len()];
        for &(key, _) in own() {
            next[(key - lo) as usize] += 1;
        }
        let mut sum = 0;
        for (n, p) in next.iter_mut().zip(ptr_part.iter_mut()) {
            let count = *n;
            *n = sum;
            sum += count;
            *p = bucket_start[b] + sum;
        }
        for &(key, value) in own() {
            let k = (key - lo) as usize;
            out[next[k]] = value;
            next[k] += 1;
        }
    });
    (ptr, values)
}

/// A chunk of items' entries sorted by bucket in [`group_by_key`]: where each bucket starts,
/// and the entries.
type BucketedChunk<T> = (Vec<usize>, Vec<(u32, T)>);

/// Keys from which [`group_by_key`] runs on all threads.
const PARALLEL_KEYS: usize = 1 << 16;

/// Whether the keys of `entries` mostly follow the items' order: the first keys of 4096
/// items spread evenly through `0..m` jump by at most 8 `n_keys` in all (a sweep through
/// the keys jumps by about `n_keys`; scattered keys by about a third of it per sample).
fn keys_follow_items<T, const K: usize>(
    n_keys: usize,
    m: usize,
    entries: &impl Fn(usize) -> [Option<(u32, T)>; K],
) -> bool {
    const SAMPLES: usize = 4096;
    if m < 2 * SAMPLES {
        return true;
    }
    let step = m / SAMPLES;
    let mut previous: Option<u32> = None;
    let mut jumps = 0u64;
    for s in 0..SAMPLES {
        if let Some((key, _)) = entries(s * step).into_iter().flatten().next() {
            if let Some(p) = previous {
                jumps += u64::from(key.abs_diff(p));
            }
            previous = Some(key);
        }
    }
    jumps <= 8 * n_keys as u64
}

/// Consecutive keys per bucket of [`group_by_key`]'s passes (their counters fit in the
/// first-level cache).
const KEY_BUCKET: usize = 1 << 12;

/// [`group_by_key`] for keys that follow the items' order (or few keys): the keys are
/// split into ranges, one per thread, and each thread scans every item and keeps the
/// entries it owns (its counters are then written in a sweep through its range).
fn group_by_key_by_ranges<T, const K: usize>(
    n_keys: usize,
    m: usize,
    entries: impl Fn(usize) -> [Option<(u32, T)>; K] + Sync,
) -> (Vec<usize>, Vec<T>)
where
    T: Copy + Default + Send + Sync,
{
    let parts = if n_keys >= PARALLEL_KEYS {
        rayon::current_num_threads().clamp(1, 16)
    } else {
        1
    };
    let bounds: Vec<usize> = (0..=parts).map(|p| p * n_keys / parts).collect();
    // Counts of each range's keys, then their running sums within the range.
    let mut ptr = filled(n_keys + 1, 0usize);
    let mut ranges = Vec::with_capacity(parts);
    let mut rest = &mut ptr[1..];
    for w in bounds.windows(2) {
        let (head, tail) = rest.split_at_mut(w[1] - w[0]);
        ranges.push((w[0], head));
        rest = tail;
    }
    let count = |(lo, counts): (usize, &mut [usize])| {
        let hi = lo + counts.len();
        for i in 0..m {
            for e in entries(i) {
                let Some((key, _)) = e else { continue };
                let key = key as usize;
                if key >= lo && key < hi {
                    counts[key - lo] += 1;
                }
            }
        }
        let mut sum = 0;
        for c in counts.iter_mut() {
            sum += *c;
            *c = sum;
        }
        sum
    };
    let totals: Vec<usize> = if parts > 1 {
        ranges.into_par_iter().map(count).collect()
    } else {
        ranges.into_iter().map(count).collect()
    };
    let mut offset = 0;
    for (w, total) in bounds.windows(2).zip(&totals) {
        if offset > 0 {
            ptr[w[0] + 1..=w[1]]
                .par_iter_mut()
                .for_each(|p| *p += offset);
        }
        offset += total;
    }
    // Each range fills its own part of the values, in item order.
    let mut values = filled(offset, T::default());
    let mut pieces = Vec::with_capacity(parts);
    let mut rest = &mut values[..];
    for w in bounds.windows(2) {
        let (head, tail) = rest.split_at_mut(ptr[w[1]] - ptr[w[0]]);
        pieces.push((w[0], w[1], head));
        rest = tail;
    }
    let ptr_ref = &ptr;
    let fill = |(lo, hi, out): (usize, usize, &mut [T])| {
        let base = ptr_ref[lo];
        let mut next: Vec<usize> = ptr_ref[lo..hi].iter().map(|p| p - base).collect();
        for i in 0..m {
            for e in entries(i) {
                let Some((key, value)) = e else { continue };
                let key = key as usize;
                if key >= lo && key < hi {
                    out[next[key - lo]] = value;
                    next[key - lo] += 1;
                }
            }
        }
    };
    if parts > 1 {
        pieces.into_par_iter().for_each(fill);
    } else {
        pieces.into_iter().for_each(fill);
    }
    (ptr, values)
}

/// Splits the value array of a matrix on `pattern` into blocks of `rows` consecutive rows:
/// `(first row, values of those rows)`, so that blocks can be filled in parallel.
pub(crate) fn row_chunks<'a>(
    pattern: &Pattern,
    val: &'a mut [f64],
    rows: usize,
) -> Vec<(usize, &'a mut [f64])> {
    let n = pattern.n();
    let mut out = Vec::with_capacity(n / rows + 1);
    let mut rest = val;
    let mut start = 0;
    while start < n {
        let end = (start + rows).min(n);
        let len = pattern.ptr(end) - pattern.ptr(start);
        let (head, tail) = rest.split_at_mut(len);
        out.push((start, head));
        rest = tail;
        start = end;
    }
    out
}

/// Below this many rows, loops run serially (threads cost more than they save).
pub const VECTOR_ROWS: usize = 16_384;

/// Runs `f(i, &mut x[i])` over all rows, in parallel for long vectors.
#[inline]
pub fn par_rows<T: Send>(x: &mut [T], f: impl Fn(usize, &mut T) + Sync + Send) {
    if x.len() >= VECTOR_ROWS {
        x.par_iter_mut()
            .enumerate()
            .with_min_len(4096)
            .for_each(|(i, xi)| f(i, xi));
    } else {
        for (i, xi) in x.iter_mut().enumerate() {
            f(i, xi);
        }
    }
}

/// `dst = src`, on all threads for long vectors.
pub fn par_copy_from(dst: &mut [f64], src: &[f64]) {
    par_rows(dst, |i, d| *d = src[i]);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 1-D Laplacian tridiag(-1, 2, -1).
    fn lap1d(n: usize) -> Csr {
        let mut t = Vec::new();
        for i in 0..n {
            t.push((i, i, 2.0));
            if i > 0 {
                t.push((i, i - 1, -1.0));
                t.push((i - 1, i, -1.0));
            }
        }
        Csr::from_triplets(n, &t)
    }

    /// `group_by_key` of `entries` against lists filled item by item, on 1 to 3 threads.
    fn check_grouping<const K: usize>(
        n_keys: usize,
        m: usize,
        entries: impl Fn(usize) -> [Option<(u32, u64)>; K] + Sync,
    ) {
        let mut lists = vec![Vec::new(); n_keys];
        for i in 0..m {
            for (key, value) in entries(i).into_iter().flatten() {
                if (key as usize) < n_keys {
                    lists[key as usize].push(value);
                }
            }
        }
        for threads in [1, 2, 3] {
            let (ptr, values) =
                crate::parallel::on_threads(threads, || group_by_key(n_keys, m, &entries));
            assert_eq!(ptr.len(), n_keys + 1);
            assert_eq!(values.len(), ptr[n_keys]);
            for (k, list) in lists.iter().enumerate() {
                assert_eq!(
                    &values[ptr[k]..ptr[k + 1]],
                    &list[..],
                    "key {k}, {threads} threads"
                );
            }
        }
    }

    #[test]
    fn grouping_by_key_is_a_stable_counting_sort_for_any_thread_count() {
        // Two entries per item, some missing, beyond the parallel size; keys scattered
        // (sorted by buckets) and keys following the items (split into ranges).
        let (n_keys, m) = (70_000, 150_000);
        let scattered = |i: usize| {
            let a = ((i * 7919) % n_keys) as u32;
            // Now and then a key out of range, left out.
            let b = ((i * 104_729 + 13) % (n_keys + 50)) as u32;
            [
                Some((a, i as u64)),
                (!i.is_multiple_of(3)).then_some((b, (i as u64) << 32)),
            ]
        };
        assert!(!keys_follow_items(n_keys, m, &scattered));
        check_grouping(n_keys, m, scattered);
        let local = |i: usize| {
            let a = (i * n_keys / m) as u32;
            [
                Some((a, i as u64)),
                (!i.is_multiple_of(3)).then_some(((a + 1).min(n_keys as u32 - 1), 7)),
            ]
        };
        assert!(keys_follow_items(n_keys, m, &local));
        check_grouping(n_keys, m, local);
        // No entries at all, and fewer keys than a bucket holds past the last one.
        check_grouping(n_keys, m, |_| [None::<(u32, u64)>]);
        check_grouping(PARALLEL_KEYS + 5, 20_000, |i| {
            [Some((((i * 7919) % (PARALLEL_KEYS + 5)) as u32, i as u64))]
        });
    }

    #[test]
    fn large_products_and_diagonals_ignore_the_thread_count() {
        // Beyond PAR_ROWS the kernels run in parallel; their results must not move.
        let n = 3 * PAR_ROWS + 17;
        let a = lap1d(n);
        let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        let run = |threads: usize| {
            crate::parallel::on_threads(threads, || {
                (a.quad_form(&x), a.diag(), a.pattern.diagonal_positions())
            })
        };
        let (q1, d1, p1) = run(1);
        assert_eq!((q1, d1.clone(), p1.clone()), run(3));
        // xᵀAx = Σ (x_i − x_{i−1})² + x_0² + x_{n−1}² for tridiag(−1, 2, −1).
        let exact: f64 = x[0] * x[0]
            + x[n - 1] * x[n - 1]
            + x.windows(2).map(|w| (w[1] - w[0]).powi(2)).sum::<f64>();
        assert!((q1 - exact).abs() <= 1e-10 * exact);
        assert!(d1.iter().all(|&d| d == 2.0));
        assert!(p1
            .iter()
            .enumerate()
            .all(|(i, &k)| a.pattern.col[k] as usize == i));
        let mut b = a.clone();
        assert!(b.is_finite());
        b.val[2 * PAR_ROWS] = f64::NAN;
        assert!(!b.is_finite());
    }

    #[test]
    fn zeroed_vectors_are_zeros_of_the_length_asked() {
        for n in [0, 1, PAR_ROWS - 1, PAR_ROWS, 3 * PAR_ROWS + 7] {
            let v = zeroed(n);
            assert_eq!(v.len(), n);
            assert!(v.iter().all(|&x| x.to_bits() == 0), "n = {n}");
        }
    }

    #[test]
    fn filled_vectors_hold_the_value_asked() {
        for n in [0, 1, PAR_ROWS - 1, PAR_ROWS, 3 * PAR_ROWS + 7] {
            let b = filled(n, true);
            assert_eq!(b.len(), n);
            assert!(b.iter().all(|&x| x), "n = {n}");
            let m = filled(n, u32::MAX);
            assert_eq!(m.len(), n);
            assert!(m.iter().all(|&x| x == u32::MAX), "n = {n}");
        }
    }

    #[test]
    fn a_pattern_from_blocks_is_their_rows_in_order() {
        // Rows i of n: columns i - 1, i, i + 1 within 0..n, cut into blocks of uneven sizes
        // (one empty), against the same rows laid out by hand.
        let n = 2 * PAR_ROWS + 5;
        let row = |i: usize| -> Vec<u32> {
            (i.saturating_sub(1)..(i + 2).min(n))
                .map(|j| j as u32)
                .collect()
        };
        let cuts = [0, 7, 7, PAR_ROWS, PAR_ROWS + 1, n];
        let blocks: Vec<(Vec<u32>, Vec<u32>)> = cuts
            .windows(2)
            .map(|w| {
                let rows: Vec<Vec<u32>> = (w[0]..w[1]).map(row).collect();
                (rows.iter().map(|r| r.len() as u32).collect(), rows.concat())
            })
            .collect();
        let p = Pattern::from_blocks(&blocks);
        assert_eq!(p.n(), n);
        assert_eq!(p.ptr(0), 0);
        for i in 0..n {
            assert_eq!(&p.col[p.ptr(i)..p.ptr(i + 1)], &row(i)[..], "row {i}");
        }
        assert_eq!(p.nnz(), 3 * n - 2);
        assert_eq!(
            Pattern::from_blocks(&[]),
            Pattern {
                row_ptr: vec![0],
                col: vec![]
            }
        );
    }

    #[test]
    fn vector_reductions_ignore_the_thread_count() {
        let n = 3 * PAR_ROWS + 17;
        // Entries of mixed sizes, so that the order of the additions shows in the rounding.
        let x: Vec<f64> = (0..n)
            .map(|i| (i as f64 * 0.37).sin() * 1e3f64.powi(i as i32 % 5))
            .collect();
        let y: Vec<f64> = (0..n).map(|i| (i as f64 * 0.11).cos()).collect();
        let run =
            |threads: usize| crate::parallel::on_threads(threads, || (dot(&x, &y), norm_inf(&x)));
        let (d1, m1) = run(1);
        assert_eq!((d1, m1), run(2));
        assert_eq!((d1, m1), run(3));
        // Against a sum in extended precision (pairs of f64: the Kahan–Babuška sum).
        let (mut s, mut c) = (0.0f64, 0.0f64);
        for (a, b) in x.iter().zip(&y) {
            let p = a * b;
            let t = s + p;
            c += if s.abs() >= p.abs() {
                (s - t) + p
            } else {
                (p - t) + s
            };
            s = t;
        }
        let exact = s + c;
        let size: f64 = x.iter().zip(&y).map(|(a, b)| (a * b).abs()).sum();
        assert!((d1 - exact).abs() <= 1e-14 * size, "{d1} against {exact}");
        assert_eq!(m1, x.iter().fold(0.0f64, |m, v| m.max(v.abs())));
        // The first non-finite entry, wherever it is.
        let mut z = y.clone();
        assert_eq!(first_non_finite(&z), None);
        z[n - 3] = f64::INFINITY;
        z[2 * PAR_ROWS + 5] = f64::NAN;
        assert_eq!(first_non_finite(&z), Some(2 * PAR_ROWS + 5));
        assert_eq!(first_non_finite(&z[..10]), None);
    }

    #[test]
    fn cholesky_solves_and_refactors() {
        let mut a = lap1d(50);
        let x: Vec<f64> = (0..50).map(|i| (i as f64 * 0.3).sin()).collect();
        let mut b = a.mul(&x);
        let mut c = Cholesky::new(&a).unwrap();
        c.solve_in_place(&mut b);
        for (p, q) in b.iter().zip(&x) {
            assert!((p - q).abs() < 1e-12);
        }
        for v in a.val.iter_mut() {
            *v *= 3.0;
        }
        c.refactor(&a).unwrap();
        let mut b = a.mul(&x);
        c.solve_in_place(&mut b);
        for (p, q) in b.iter().zip(&x) {
            assert!((p - q).abs() < 1e-12);
        }
    }

    #[test]
    fn indefinite_matrix_is_an_error() {
        let mut a = lap1d(5);
        for v in a.val.iter_mut() {
            *v = -*v;
        }
        assert!(Cholesky::new(&a).is_err());
    }

    #[test]
    fn triplets_sum_duplicates() {
        let a = Csr::from_triplets(2, &[(0, 0, 1.0), (0, 0, 2.0), (1, 0, 4.0)]);
        assert_eq!(a.get(0, 0), 3.0);
        assert_eq!(a.get(1, 0), 4.0);
        assert_eq!(a.get(0, 1), 0.0);
        assert_eq!(a.quad_form(&[1.0, 1.0]), 7.0);
    }
}
