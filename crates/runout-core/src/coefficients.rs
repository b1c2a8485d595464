//! Mechanistic cutting coefficients (Altintas): shear K_tc, K_rc, K_ac (N/mm²) and edge
//! K_te, K_re, K_ae (N/mm).

use crate::error::{finite, ParamError};

/// Cutting force coefficients. dF_t = K_tc·h·dz + K_te·dz (for h > 0), likewise r and a.
///
/// ```
/// use runout_core::CuttingCoefficients;
/// let k = CuttingCoefficients::new([1889.2, 806.1, 291.0], [63.12, 113.7, -3.1]).unwrap();
/// assert_eq!(k.without_edge().kte, 0.0);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CuttingCoefficients {
    /// Tangential shear coefficient (N/mm²).
    pub ktc: f64,
    /// Radial shear coefficient (N/mm²).
    pub krc: f64,
    /// Axial shear coefficient (N/mm²).
    pub kac: f64,
    /// Tangential edge coefficient (N/mm).
    pub kte: f64,
    /// Radial edge coefficient (N/mm).
    pub kre: f64,
    /// Axial edge coefficient (N/mm).
    pub kae: f64,
}

impl CuttingCoefficients {
    /// From `[K_tc, K_rc, K_ac]` (N/mm²) and `[K_te, K_re, K_ae]` (N/mm).
    pub fn new(shear: [f64; 3], edge: [f64; 3]) -> Result<Self, ParamError> {
        let names = ["ktc", "krc", "kac", "kte", "kre", "kae"];
        for (n, v) in names.iter().zip(shear.iter().chain(edge.iter())) {
            finite(n, *v)?;
        }
        Ok(CuttingCoefficients {
            ktc: shear[0],
            krc: shear[1],
            kac: shear[2],
            kte: edge[0],
            kre: edge[1],
            kae: edge[2],
        })
    }

    /// The same shear coefficients with the edge coefficients set to zero.
    pub fn without_edge(&self) -> Self {
        CuttingCoefficients {
            kte: 0.0,
            kre: 0.0,
            kae: 0.0,
            ..*self
        }
    }

    /// As an array `[K_tc, K_rc, K_ac, K_te, K_re, K_ae]`.
    pub fn to_array(&self) -> [f64; 6] {
        [self.ktc, self.krc, self.kac, self.kte, self.kre, self.kae]
    }

    /// From an array `[K_tc, K_rc, K_ac, K_te, K_re, K_ae]`.
    pub fn from_array(a: [f64; 6]) -> Self {
        CuttingCoefficients {
            ktc: a[0],
            krc: a[1],
            kac: a[2],
            kte: a[3],
            kre: a[4],
            kae: a[5],
        }
    }
}
