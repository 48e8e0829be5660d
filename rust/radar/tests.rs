use super::gamma::{
    inverse_upper, ln_factorial, ln_scaled_lower, lower_and_term_below, reciprocal, regularized, term, upper,
    upper_and_term,
};
use super::*;

const CASES: [Swerling; 5] = [
    Swerling::Zero,
    Swerling::One,
    Swerling::Two,
    Swerling::Three,
    Swerling::Four,
];

fn pd(case: Swerling, n: u64, snr_db: f64, pfa: f64) -> f64 {
    let t = inverse_upper(n, pfa);
    detection_probability(case, n, 10f64.powf(snr_db / 10.0), t, pfa)
}

#[test]
fn the_threshold_gives_the_false_alarm_probability() {
    for n in [1, 2, 5, 30, 300] {
        for pfa in [1e-2, 1e-6, 1e-10] {
            let t = inverse_upper(n, pfa);
            assert!((upper(n, t) / pfa - 1.0).abs() < 1e-12, "n {n} pfa {pfa}");
        }
    }
}

#[test]
fn p_and_q_add_to_one_and_scaled_lower_tends_to_its_limit() {
    for (a, x) in [(1, 0.5), (3, 2.0), (3, 7.0), (40, 39.0), (40, 41.0), (500, 480.0)] {
        let (p, q) = regularized(a, x);
        assert!((p + q - 1.0).abs() < 1e-15 && p > 0.0 && q > 0.0);
    }
    // X_a(c, T) → T^a / a! as c → 0, and X_a(1, T) = P(a, T)
    let (a, t) = (4u64, 3.0f64);
    assert!((ln_scaled_lower(a, 0.0, t).exp() - t.powi(4) / 24.0).abs() < 1e-14);
    assert!((ln_scaled_lower(a, 1.0, t).exp() - regularized(a, t).0).abs() < 1e-15);
}

#[test]
fn the_sums_starting_points_are_the_functions_and_terms_they_stand_for() {
    // the reciprocal table is the division, bit for bit, and so is the fallback past it
    for j in (1..5000u64).chain([1 << 40, u64::MAX]) {
        assert_eq!(reciprocal(j).to_bits(), (1.0 / j as f64).to_bits(), "{j}");
    }
    // each start pairs P or Q with the term next to it, the one derived from the other
    // as close as two terms formed in logs are to each other (each carries the rounding of
    // −x + j ln x − ln j!, ~(x + j|ln x|)ε), on both sides of x = a and into the underflow
    for (a, x) in [
        (1, 0.5),
        (10, 33.0),
        (10, 3.0),
        (40, 39.5),
        (300, 20.0),
        (700, 1.0),
        (5, 900.0),
    ] {
        let (p, q) = regularized(a, x);
        let (q_start, at) = upper_and_term(a, x);
        let (p_start, below) = lower_and_term_below(a, x);
        assert_eq!((q_start, p_start), (q, p));
        let logs = 4.0 * f64::EPSILON * (x + a as f64 * x.ln().abs() + ln_factorial(a));
        for (got, want) in [(at, term(a, x)), (below, term(a - 1, x))] {
            assert!(
                got == want || (got / want - 1.0).abs() < logs,
                "a {a} x {x}: {got:e} {want:e}"
            );
        }
    }
}

#[test]
fn one_pulse_closed_forms_and_coinciding_cases() {
    let pfa = 1e-6f64;
    for snr_db in [-10.0, 0.0, 13.0, 30.0] {
        let s = 10f64.powf(snr_db / 10.0);
        let sw1 = pd(Swerling::One, 1, snr_db, pfa);
        assert!((sw1 - pfa.powf(1.0 / (1.0 + s))).abs() < 1e-14 * sw1.max(1e-300) + 1e-16);
        assert_eq!(sw1.to_bits(), pd(Swerling::One, 1, snr_db, pfa).to_bits());
        // one pulse: scan-to-scan and pulse-to-pulse fluctuation are the same thing
        assert!((pd(Swerling::Two, 1, snr_db, pfa) / sw1 - 1.0).abs() < 1e-12);
        let (sw3, sw4) = (pd(Swerling::Three, 1, snr_db, pfa), pd(Swerling::Four, 1, snr_db, pfa));
        assert!((sw3 / sw4 - 1.0).abs() < 1e-12, "{sw3} {sw4}");
    }
}

#[test]
fn p_d_rises_from_the_false_alarm_probability_to_one() {
    for case in CASES {
        for n in [1, 3, 10] {
            let t = inverse_upper(n, 1e-6);
            // (the one-pulse closed forms give e^{ln P_FA}: within an ulp or two of P_FA)
            assert!((detection_probability(case, n, 0.0, t, 1e-6) / 1e-6 - 1.0).abs() < 1e-15);
            assert_eq!(detection_probability(case, n, f64::INFINITY, t, 1e-6), 1.0);
            assert_eq!(detection_probability(case, n, f64::MAX, t, 1e-6), 1.0);
            let mut last = 1e-6 * (1.0 - 1e-15);
            for tenth_db in -200..=600 {
                let p = pd(case, n, f64::from(tenth_db) / 10.0, 1e-6);
                assert!(
                    p >= last * (1.0 - 1e-12) && p <= 1.0,
                    "{case:?} n {n} {tenth_db}: {p} < {last}"
                );
                last = p;
            }
            assert!(last > 0.99, "{case:?} n {n}: {last}");
        }
        // the most pulses: sums whose terms overflow on their own stay finite
        let n = MAX_PULSES;
        let mut last = 0.0;
        for db in [-60.0, -30.0, -20.0, -15.0, -10.0, -5.0, 0.0, 10.0, 40.0] {
            let p = pd(case, n, db, 1e-6);
            assert!(
                p.is_finite() && p >= last && (1e-6 * (1.0 - 1e-9)..=1.0).contains(&p),
                "{case:?} {db}: {p}"
            );
            last = p;
        }
        assert!(last > 0.9999, "{case:?}: {last}"); // (Swerling 1: a deep fade of the one σ stays possible)
    }
}

#[test]
fn the_equation_falls_with_the_fourth_power_of_range() {
    let radar = RadarEquation::new(20.0, 1000.0, 3.0, 1e-6, Swerling::One, 1).unwrap();
    assert!((radar.snr_at_squared(1000.0 * 1000.0) - 10f64.powf(1.7)).abs() < 1e-12);
    assert!((radar.snr_at_squared(2000.0 * 2000.0) * 16.0 / 10f64.powf(1.7) - 1.0).abs() < 1e-14);
    assert_eq!(radar.at(0.0), 1.0);
    assert!(radar.at(f64::NAN).is_nan());
    assert!((radar.at(1e9) - 1e-6).abs() < 1e-12);
    // r⁴ overflows beyond 1e77 m: S = 0 there, P_D = P_FA (not ∞/∞)
    for r in [1e78, 1e100, f64::INFINITY] {
        assert!((radar.at(r) / 1e-6 - 1.0).abs() < 1e-14, "{r}");
    }
    // the one-pulse form at range against P_FA^(1/(1+S)) with S from the SNR
    for r in [1.0, 300.0, 1000.0, 2500.0, 1e5] {
        let s = radar.snr_at_squared(r * r);
        assert!((radar.at(r) / 1e-6f64.powf(1.0 / (1.0 + s)) - 1.0).abs() < 1e-13, "{r}");
    }
}

#[test]
fn bad_parameters_name_their_argument() {
    let cases = [
        (
            RadarEquation::new(f64::NAN, 1.0, 0.0, 1e-6, Swerling::Zero, 1),
            "reference_snr",
        ),
        (
            RadarEquation::new(10.0, 0.0, 0.0, 1e-6, Swerling::Zero, 1),
            "reference_range",
        ),
        (RadarEquation::new(10.0, 1.0, -1.0, 1e-6, Swerling::Zero, 1), "loss"),
        (
            RadarEquation::new(10.0, 1.0, 0.0, 1.0, Swerling::Zero, 1),
            "false_alarm_probability",
        ),
        (
            RadarEquation::new(10.0, 1.0, 0.0, 0.0, Swerling::Zero, 1),
            "false_alarm_probability",
        ),
        (RadarEquation::new(10.0, 1.0, 0.0, 1e-6, Swerling::Zero, 0), "pulses"),
        (
            RadarEquation::new(10.0, 1.0, 0.0, 1e-6, Swerling::Zero, MAX_PULSES + 1),
            "pulses",
        ),
    ];
    for (result, argument) in cases {
        assert_eq!(result.unwrap_err().argument(), argument);
    }
    assert_eq!(Swerling::from_case(5).unwrap_err().argument(), "swerling");
}
