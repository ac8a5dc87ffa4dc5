//! Run-time choice of an AVX2 build of the hot algorithms.
//!
//! The crate is compiled for the baseline target (x86-64 SSE2 by default),
//! so the same binary runs everywhere. The chain path's
//! [`forward_dynamics`], [`inverse_dynamics`], [`mass_matrix`], the shifted
//! factorization and the inverse-dynamics derivatives (its outward sweep
//! inlined) are each compiled twice — as is,
//! and with AVX2 enabled (wider vectors, three-operand encodings) — and the
//! AVX2 copy runs when the CPU has it. FMA is deliberately not enabled and
//! Rust never contracts `a * b + c` on its own, so both copies perform the
//! same IEEE operations in the same order: their results are bit-identical
//! (tested below). Measured on the 2-core development VM:
//! ~10 % less time per call (docs/performance.md).
//!
//! The copies exist with the cargo feature `avx2` (on by default; the
//! facade `softrod` and the benches forward it). Without it
//! (`--no-default-features`) only the baseline copy runs, which is how the
//! callgrind instruction counts in docs/performance.md are taken: valgrind
//! 3.19 does not decode every AVX instruction the AVX2 copy uses.
//!
//! [`forward_dynamics`]: crate::forward_dynamics
//! [`inverse_dynamics`]: crate::inverse_dynamics
//! [`mass_matrix`]: crate::mass_matrix

/// Whether the AVX2 copies may run: detected once, then one atomic load.
#[cfg(target_arch = "x86_64")]
#[inline]
pub(crate) fn avx2() -> bool {
    static FLAG: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *FLAG.get_or_init(|| cfg!(feature = "avx2") && std::arch::is_x86_feature_detected!("avx2"))
}

/// Defines `fn $name` (with the visibility given) that dispatches to an
/// AVX2 or a baseline copy of `$imp` (an `#[inline(always)]` function with
/// the same signature, whose callees that matter are inlined into it too),
/// and the AVX2 copy `$avx`. The one `unsafe` call of the crate is here:
/// the AVX2 copy, after the run-time check of the CPU.
macro_rules! dispatch {
    (
        $(#[$meta:meta])*
        $vis:vis fn $name:ident $(<$lt:lifetime>)? ($($arg:ident: $ty:ty),* $(,)?) $(-> $ret:ty)?
        => $imp:ident, $avx:ident
    ) => {
        $(#[$meta])*
        #[allow(unsafe_code)]
        $vis fn $name $(<$lt>)? ($($arg: $ty),*) $(-> $ret)? {
            #[cfg(target_arch = "x86_64")]
            if crate::kernels::simd::avx2() {
                // SAFETY: the CPU supports AVX2 (checked at run time).
                return unsafe { $avx($($arg),*) };
            }
            $imp($($arg),*)
        }

        /// The AVX2 copy of the same code (bit-identical results).
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2")]
        pub(crate) fn $avx $(<$lt>)? ($($arg: $ty),*) $(-> $ret)? {
            $imp($($arg),*)
        }
    };
}

pub(crate) use dispatch;

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use crate::algorithms::chain::{
        forward_dynamics_avx2, forward_dynamics_impl, inverse_dynamics_avx2, inverse_dynamics_impl,
        mass_matrix_avx2, mass_matrix_impl,
    };
    use crate::{Data, Model, Rod};
    use nalgebra::Matrix6xX;
    use softrod_kinematics::{Basis, PieceSpec, RodGeometry, Strain};
    use softrod_lie::{Vec3, Vec6, exp_twist};
    use softrod_mechanics::{
        DistributedLoad, Drag, LoadFrame, Material, PointLoad, RodProperties, Section,
    };

    /// Mixed bases (identity, selections, Kirchhoff, a general 6×4), every
    /// force term, and strains on both sides of the series switch.
    fn model() -> Model {
        let bases = [
            Basis::all(),
            Basis::select(&[Strain::Ky, Strain::Qx]).unwrap(),
            Basis::kirchhoff(),
            Basis::from_matrix(Matrix6xX::from_fn(4, |i, j| {
                ((i * 4 + j) as f64 * 0.9 + 0.3).sin() + if i == j { 1.5 } else { 0.0 }
            }))
            .unwrap(),
        ];
        let specs = (0..9)
            .map(|i| PieceSpec {
                length: 0.1,
                basis: bases[i % bases.len()].clone(),
                rest_strain: Vec6::new(0.1, 0.5, -0.3, 1.0, 0.0, 0.0),
            })
            .collect();
        let base = exp_twist(1.0, &Vec6::new(0.2, -0.4, 0.1, 0.0, 0.05, 0.1));
        let rod = RodGeometry::from_pieces(specs, base).unwrap();
        let body = RodProperties::new(
            Section::Circle { radius: 0.012 },
            Material::builder()
                .density(1100.0)
                .young(2e6)
                .poisson(0.45)
                .viscosity(30.0)
                .build()
                .unwrap(),
            0.9,
        )
        .unwrap();
        let mut spec = Rod::new("arm", rod, body);
        spec.point_loads = vec![PointLoad {
            s: 0.37,
            force: Vec3::new(-0.05, 0.1, 0.0),
            moment: Vec3::new(0.0, 0.01, 0.0),
            frame: LoadFrame::Body,
        }];
        spec.distributed_loads = vec![DistributedLoad {
            force: Vec3::new(0.0, 0.3, 0.1),
            moment: Vec3::zeros(),
            frame: LoadFrame::World,
        }];
        spec.drag = Some(Drag {
            translational: 0.5,
            rotational: 1e-4,
        });
        Model::new(vec![spec], Some(Vec3::new(0.3, -1.0, -9.81)), 4).unwrap()
    }

    #[test]
    fn avx2_copies_are_bit_identical_to_the_baseline() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            eprintln!("no AVX2 on this CPU: only the baseline copy exists at run time");
            return;
        }
        let model = model();
        let n = model.n_dof();
        // Curvatures up to ~40 rad/m on 0.1 m pieces: ψ from 0 past the
        // series switch (2.5) to several radians.
        let q: Vec<f64> = (0..n).map(|i| ((i * 37 % 11) as f64 - 5.0) * 8.0).collect();
        let qd: Vec<f64> = (0..n).map(|i| ((i * 13 % 7) as f64 - 3.0) * 0.7).collect();
        let qdd: Vec<f64> = (0..n).map(|i| ((i * 5 % 9) as f64 - 4.0) * 3.0).collect();
        let (mut d1, mut d2) = (Data::new(&model), Data::new(&model));
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();

        inverse_dynamics_impl(&model, &mut d1, crate::Forces::ALL, 0.3, &q, &qd, &qdd);
        // SAFETY: AVX2 detected above.
        unsafe { inverse_dynamics_avx2(&model, &mut d2, crate::Forces::ALL, 0.3, &q, &qd, &qdd) };
        let (a, b) = (&d1.tau, &d2.tau);
        assert!(a.iter().all(|x| x.is_finite()) && a.amax() > 0.0);
        assert_eq!(bits(a.as_slice()), bits(b.as_slice()), "inverse dynamics");

        forward_dynamics_impl(&model, &mut d1, crate::Forces::ALL, 0.3, &q, &qd, None).unwrap();
        // SAFETY: as above.
        unsafe { forward_dynamics_avx2(&model, &mut d2, crate::Forces::ALL, 0.3, &q, &qd, None) }
            .unwrap();
        let (a, b) = (&d1.qdd, &d2.qdd);
        assert!(a.iter().all(|x| x.is_finite()) && a.amax() > 0.0);
        assert_eq!(bits(a.as_slice()), bits(b.as_slice()), "forward dynamics");

        let mut w1 = crate::IdDerivatives::new(&model);
        let mut w2 = crate::IdDerivatives::new(&model);
        crate::derivatives::id_derivatives_impl(
            &model,
            &mut w1,
            crate::Forces::ALL,
            0.3,
            &q,
            &qd,
            &qdd,
        )
        .unwrap();
        // SAFETY: as above.
        unsafe {
            crate::derivatives::id_derivatives_avx2(
                &model,
                &mut w2,
                crate::Forces::ALL,
                0.3,
                &q,
                &qd,
                &qdd,
            )
        }
        .unwrap();
        assert!(w1.dtau_dq.amax() > 0.0);
        assert_eq!(
            bits(w1.dtau_dq.as_slice()),
            bits(w2.dtau_dq.as_slice()),
            "dτ/dq"
        );
        assert_eq!(
            bits(w1.dtau_dqd.as_slice()),
            bits(w2.dtau_dqd.as_slice()),
            "dτ/dq̇"
        );

        crate::algorithms::shifted::shifted_factor_impl(&model, &mut d1, &q, 1e-4, 1e-2, None)
            .unwrap();
        // SAFETY: as above.
        unsafe {
            crate::algorithms::shifted::shifted_factor_avx2(&model, &mut d2, &q, 1e-4, 1e-2, None)
        }
        .unwrap();
        for (p1, p2) in d1.pieces[0].iter().zip(&d2.pieces[0]) {
            assert_eq!(
                bits(p1.dt.as_slice()),
                bits(p2.dt.as_slice()),
                "shifted factor"
            );
            assert_eq!(
                bits(p1.ut.as_slice()),
                bits(p2.ut.as_slice()),
                "shifted factor"
            );
        }

        mass_matrix_impl(&model, &mut d1, &q);
        // SAFETY: as above.
        unsafe { mass_matrix_avx2(&model, &mut d2, &q) };
        let (a, b) = (&d1.mass, &d2.mass);
        assert_eq!(bits(a.as_slice()), bits(b.as_slice()), "mass matrix");
    }
}
