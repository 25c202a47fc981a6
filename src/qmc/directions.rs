//! Joe and Kuo's Sobol' direction numbers (`new-joe-kuo-6.21201`: S. Joe and
//! F. Y. Kuo, "Constructing Sobol sequences with better two-dimensional
//! projections", SIAM J. Sci. Comput. 30(5), 2008), the table scipy's
//! `qmc.Sobol` uses, packed by `tools/pack_sobol_directions.py`.

/// The packed table: per dimension 1 .. [`MAX_DIMENSIONS`] − 1, the
/// primitive polynomial in 3 bytes, then its degree `s` initial numbers
/// `m_1 .. m_s` in 1, 2 or 3 bytes each (`m_k < 2^k`), little-endian.
static TABLE: &[u8] = include_bytes!("joe_kuo.bin");

/// Dimensions the table covers (scipy's `Sobol.MAXDIM`).
pub const MAX_DIMENSIONS: usize = 21201;

/// Bits of each coordinate: points are `x/2^32`, for indices below `2^32`.
pub const BITS: usize = 32;

/// The generator matrices of the first `dims` dimensions, as columns:
/// `v[j] = m_{j+1}·2^{31−j}`, with `m` continued past the polynomial's
/// degree `s` (coefficients `a_1 .. a_{s−1}` between its leading and
/// constant terms) by Bratley and Fox's recurrence
///
/// `m_j = 2^s m_{j−s} ⊕ m_{j−s} ⊕ ⊕_{k=1}^{s−1} a_k 2^k m_{j−k}`.
///
/// Dimension 0 is van der Corput's (`m_j = 1`). `dims` ≤
/// [`MAX_DIMENSIONS`] (the caller checks).
pub(crate) fn columns(dims: usize) -> Vec<[u32; BITS]> {
    let mut out = Vec::with_capacity(dims);
    out.push(std::array::from_fn(|j| 1u32 << (BITS - 1 - j)));
    let mut bytes = TABLE;
    for _ in 1..dims {
        let poly = take(&mut bytes, 3);
        let degree = (u32::BITS - 1 - poly.leading_zeros()) as usize;
        let mut m = [0u32; BITS];
        for (k, m_k) in m.iter_mut().enumerate().take(degree) {
            *m_k = take(&mut bytes, width(k + 1));
        }
        for j in degree..BITS {
            m[j] = (1..=degree)
                .filter(|&k| (poly >> (degree - k)) & 1 == 1)
                .fold(m[j - degree], |acc, k| acc ^ (m[j - k] << k));
        }
        out.push(std::array::from_fn(|j| m[j] << (BITS - 1 - j)));
    }
    out
}

/// Bytes that hold `m_k` in the table.
fn width(k: usize) -> usize {
    match k {
        0..=8 => 1,
        9..=16 => 2,
        _ => 3,
    }
}

/// The next `n` bytes of `bytes` as a little-endian number; advances.
fn take(bytes: &mut &[u8], n: usize) -> u32 {
    let (head, tail) = bytes.split_at(n);
    *bytes = tail;
    head.iter()
        .rev()
        .fold(0, |acc, &b| (acc << 8) | u32::from(b))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The table holds exactly the dimensions it claims, and each initial
    /// number is odd and below `2^k` (as direction numbers must be).
    #[test]
    fn the_table_decodes_to_its_end() {
        let mut bytes = TABLE;
        for _ in 1..MAX_DIMENSIONS {
            let poly = take(&mut bytes, 3);
            assert!(poly & 1 == 1 && poly > 1);
            let degree = (u32::BITS - 1 - poly.leading_zeros()) as usize;
            for k in 1..=degree {
                let m = take(&mut bytes, width(k));
                assert!(m % 2 == 1 && m < 1 << k);
            }
        }
        assert!(bytes.is_empty());
    }

    /// Every column `j` of every matrix has bit `31 − j` set and none
    /// below it (`m_{j+1}` is odd and below `2^{j+1}`): with bit 31 as row
    /// 0, the matrices are upper triangular with ones on the diagonal, so
    /// each dimension's first `2^m` points are the multiples of `2^−m`.
    #[test]
    fn matrices_are_unit_upper_triangular() {
        for (d, v) in columns(MAX_DIMENSIONS).iter().enumerate() {
            for (j, &c) in v.iter().enumerate() {
                let diagonal = 1u32 << (BITS - 1 - j);
                assert!(c & diagonal != 0, "dimension {d}, column {j}");
                assert_eq!(c & (diagonal - 1), 0);
            }
        }
    }
}
