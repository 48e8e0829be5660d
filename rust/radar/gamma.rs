//! The regularised incomplete gamma functions at integer shapes, which are all that square-law
//! detection of `n` pulses needs:
//!
//! P(a, x) = γ(a, x) / Γ(a),   Q(a, x) = 1 − P(a, x) = e^{−x} Σ_{j<a} x^j / j!
//!
//! (Q is the Erlang survival function). Each is summed directly where it is the smaller of
//! the two (Q's finite sum for x ≥ a, P's series e^{−x} Σ_{j≥a} x^j / j! for x < a), so
//! both keep their relative accuracy in the tails, and the terms are formed from the
//! largest one in logs, so that neither e^{−x} nor x^j overflows or underflows on its own.

/// ln k! for k ≥ 0: sums of logs below 256 (a table made once), Stirling's series above
/// (its first omitted term is below 1e-20).
pub fn ln_factorial(k: u64) -> f64 {
    static TABLE: std::sync::OnceLock<[f64; 256]> = std::sync::OnceLock::new();
    if k < 256 {
        TABLE.get_or_init(|| {
            let mut table = [0.0; 256];
            for j in 2..256 {
                table[j] = table[j - 1] + (j as f64).ln();
            }
            table
        })[k as usize]
    } else {
        let n = k as f64;
        let inv = 1.0 / n;
        let inv2 = inv * inv;
        n * n.ln() - n
            + 0.5 * (2.0 * std::f64::consts::PI * n).ln()
            + inv * (1.0 / 12.0 - inv2 * (1.0 / 360.0 - inv2 / 1260.0))
    }
}

/// The Poisson-like term e^{−x} x^j / j! (x ≥ 0), formed in logs.
pub fn term(j: u64, x: f64) -> f64 {
    if x == 0.0 {
        return if j == 0 { 1.0 } else { 0.0 };
    }
    (-x + j as f64 * x.ln() - ln_factorial(j)).exp()
}

/// 1/j, correctly rounded (a table below 2048, so that the sums' recurrences multiply
/// rather than divide; the same bits either way).
#[inline]
pub fn reciprocal(j: u64) -> f64 {
    const TABLE: [f64; 2048] = {
        let mut table = [f64::INFINITY; 2048];
        let mut j = 1;
        while j < 2048 {
            table[j] = 1.0 / j as f64;
            j += 1;
        }
        table
    };
    match TABLE.get(j as usize) {
        Some(&r) => r,
        None => 1.0 / j as f64,
    }
}

/// (P(a, x), Q(a, x)) for an integer shape `a` ≥ 0 and x ≥ 0 (x = +inf gives (1, 0)).
/// Shape 0 is the point mass at 0: P = 1.
pub fn regularized(a: u64, x: f64) -> (f64, f64) {
    if a == 0 {
        return (1.0, 0.0);
    }
    if x == f64::INFINITY {
        return (1.0, 0.0);
    }
    if x <= 0.0 {
        return (0.0, 1.0);
    }
    let (p, q, _) = with_terms(a, x);
    (p, q)
}

/// (P(a, x), Q(a, x), (t_{a−1}, t_a)) for a ≥ 1 and finite x > 0, t_j = e^{−x} x^j / j!:
/// the sums' largest term formed in logs, the other from it by one step where that keeps
/// it a normal number.
fn with_terms(a: u64, x: f64) -> (f64, f64, (f64, f64)) {
    let inverse = 1.0 / x;
    if x >= a as f64 {
        // Q = Σ_{j<a} t_j, from the largest term (j = a − 1) down: t_{j−1} = t_j j / x.
        let below = term(a - 1, x);
        let (mut t, mut q, mut j) = (below, 0.0, a - 1);
        loop {
            q += t;
            if j == 0 || t <= q * 1e-18 {
                break;
            }
            t *= j as f64 * inverse;
            j -= 1;
        }
        let q = q.min(1.0);
        (1.0 - q, q, (below, beside(below, x * reciprocal(a), || term(a, x))))
    } else {
        // P = Σ_{j≥a} t_j, from the largest term (j = a) up: t_{j+1} = t_j x / (j + 1).
        let at = term(a, x);
        let (mut t, mut p, mut j) = (at, 0.0, a);
        loop {
            p += t;
            j += 1;
            t *= x * reciprocal(j);
            if t <= p * 1e-18 {
                break;
            }
        }
        let p = p.min(1.0);
        (p, 1.0 - p, (beside(at, a as f64 * inverse, || term(a - 1, x)), at))
    }
}

/// `t · ratio`, or `direct()` where t is subnormal or zero (the step would carry its lost
/// bits).
fn beside(t: f64, ratio: f64, direct: impl Fn() -> f64) -> f64 {
    if t >= f64::MIN_POSITIVE {
        t * ratio
    } else {
        direct()
    }
}

/// (Q(a, x), t_a(x)) for a ≥ 1 and finite x > 0: where an upward sum of Q starts.
pub fn upper_and_term(a: u64, x: f64) -> (f64, f64) {
    let (_, q, (_, at)) = with_terms(a, x);
    (q, at)
}

/// (P(a, x), t_{a−1}(x)) for a ≥ 1 and finite x > 0: where a downward sum of P starts.
pub fn lower_and_term_below(a: u64, x: f64) -> (f64, f64) {
    let (p, _, (below, _)) = with_terms(a, x);
    (p, below)
}

/// Q(a, x).
pub fn upper(a: u64, x: f64) -> f64 {
    regularized(a, x).1
}

/// ln X_a(c, T), where X_a(c, T) = c^{−a} P(a, cT) = (1/Γ(a)) ∫₀^T g^{a−1} e^{−cg} dg for
/// an integer a ≥ 1, c ∈ [0, 1], T > 0: without dividing by c^a (so it holds at c → 0,
/// where X_a tends to T^a / a!), and in logs (X_a overflows for many pulses while the
/// e^{−T/γ} it is multiplied by underflows):
/// X_a = e^{−cT} T^a / a! · Σ_{i≥0} (cT)^i a! / (a + i)!.
pub fn ln_scaled_lower(a: u64, c: f64, t: f64) -> f64 {
    let ct = c * t;
    if ct > a as f64 + 1.0 {
        // the series would be long, and P(a, cT) is not small: c^{−a} P directly
        return regularized(a, ct).0.ln() - a as f64 * c.ln();
    }
    let (mut sum, mut term) = (1.0f64, 1.0);
    let mut i = 0u64;
    loop {
        i += 1;
        term *= ct / (a + i) as f64;
        sum += term;
        if term <= sum * 1e-18 {
            break;
        }
    }
    -ct + a as f64 * t.ln() - ln_factorial(a) + sum.ln()
}

/// The threshold T with Q(a, T) = `p` (0 < p < 1): the noise-only false-alarm threshold of
/// a square-law detector summing `a` pulses. Newton's method on ln Q, kept in a bracket.
pub fn inverse_upper(a: u64, p: f64) -> f64 {
    if a == 1 {
        return -p.ln();
    }
    let target = p.ln();
    // Q(a, ·) falls from 1 at 0: bracket T between lo (Q > p) and hi (Q < p).
    let (mut lo, mut hi) = (0.0f64, a as f64 + 1.0);
    while upper(a, hi) > p {
        lo = hi;
        hi *= 2.0;
    }
    let mut t = 0.5 * (lo + hi);
    for _ in 0..200 {
        let q = upper(a, t);
        if q > p {
            lo = t;
        } else {
            hi = t;
        }
        // d ln Q / dT = −t_{a−1}(T) / Q
        let slope = -term(a - 1, t) / q;
        let mut next = t - (q.ln() - target) / slope;
        if !(next > lo && next < hi && next.is_finite()) {
            next = 0.5 * (lo + hi);
        }
        if (next - t).abs() <= 1e-15 * t {
            return next;
        }
        t = next;
    }
    t
}
