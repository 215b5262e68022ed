// The solid term of a covered cell (seed eq. 7-9), appended with imb.wgsl: `solid_term` in the
// fluid kernels (FUSED), `immersed_boundary` for a covered cell with its particles from its slots,
// and `solid_collision`, one particle's Omega and the momentum it takes (for `reduce`).

// In the fluid kernels (lbm.wgsl): the collision `post` of cell k, with the solid term when FUSED
// and particles cover the cell. One mask word serves 32 consecutive cells: a warp reads it once.
fn solid_term(k: u32, f: array<f32, 19>, m: Moments, post: array<f32, 19>) -> array<f32, 19> {
    if FUSED {
        if (atomicLoad(&covered[mask_word(k)]) & mask_bit(k)) != 0u {
            return immersed_boundary(k, f, m, post);
        }
    }
    return post;
}

// The collision of a cell covered by particles (seed eq. 7): the fluid part of `post` (the
// operator's relaxation and source) is weighted by 1 - sum B, and each particle adds B_s Omega_s
// (`solid_collision`). The particles in the order of their keys (`hold_slot`'s order: the sums do
// not depend on the order of arrival), their weights B (eq. 7) from their solid fractions with the
// total capped at 1. The first two slots' keys are read once (an empty slot is 0: the cell's
// count, `slot_count`) and their particles held through the three sums (the second looked up
// where the cell has one); the others (slots 3 and 4: rare) are looked up again for each,
// since an array indexed by slot would live in memory on llvmpipe, each access a loop over the
// SIMD lanes. No loop over the slots bounded by the cell's count: llvmpipe runs a loop's body at
// least once, masked, so each such loop cost every covered cell a particle's lookup and, the
// third, a solid collision, where most cells have one particle.
fn immersed_boundary(k: u32, f: array<f32, 19>, m: Moments, post: array<f32, 19>) -> array<f32, 19> {
    let first_key = atomicLoad(&slots[k * SLOTS]);
    if first_key == 0u { return post; }
    var second_key = first_key;
    if SLOTS > 1u {
        second_key = atomicLoad(&slots[k * SLOTS + 1u]);
    }
    let count = slot_count(k, second_key);
    let first = cover_of(k, first_key);
    var second = first;
    if count > 1u {
        second = cover_of(k, second_key);
    }
    let scale = slot_scale(k, count, first.eps, second.eps);
    let b_first = weighting(first.eps * scale);
    let b_second = weighting(second.eps * scale);
    var b_total = b_first;
    if count > 1u {
        b_total += b_second;
    }
    for (var s = 2u; s < SLOTS; s++) {
        if s < count {
            b_total += weighting(slot_cover(k, s).eps * scale);
        }
    }
    var out: array<f32, 19>;
    //#for i
    out[{i}] = f[{i}] - (1.0 - b_total) * (f[{i}] - post[{i}]);
    //#end
    let own = own_collision(f, m, post);
    out = solid_collision(first.p, first.t, first.x, b_first, f, m, own, out);
    if count > 1u {
        out = solid_collision(second.p, second.t, second.x, b_second, f, m, own, out);
    }
    for (var s = 2u; s < SLOTS; s++) {
        if s < count {
            let c = slot_cover(k, s);
            out = solid_collision(c.p, c.t, c.x, weighting(c.eps * scale), f, m, own, out);
        }
    }
    return out;
}

// The factor that caps the total solid fraction of cell k's `count` particles at 1 (the first
// two's fractions given), the fractions summed in slot order.
fn slot_scale(k: u32, count: u32, first: f32, second: f32) -> f32 {
    var eps_total = first;
    if count > 1u {
        eps_total += second;
    }
    for (var s = 2u; s < SLOTS; s++) {
        if s < count {
            eps_total += slot_cover(k, s).eps;
        }
    }
    return select(1.0, 1.0 / eps_total, eps_total > 1.0);
}

// A particle covering a cell, with the cell's offset in its box, the cell's centre there and the
// cell's solid fraction.
struct Cover {
    p: Particle,
    t: vec3<i32>,
    x: vec3<f32>,
    eps: f32,
}

// How many particles covered cell k hold its slots (its first slot held), its second slot's key
// given (0 where empty): the slots fill in order (`hold_slot`).
fn slot_count(k: u32, second_key: u32) -> u32 {
    var count = 1u;
    if SLOTS > 1u && second_key != 0u {
        count = 2u;
    }
    for (var s = 2u; s < SLOTS; s++) {
        if atomicLoad(&slots[k * SLOTS + s]) != 0u {
            count = s + 1u;
        }
    }
    return count;
}

// The particle of slot s of cell k (`cover_of`).
fn slot_cover(k: u32, s: u32) -> Cover {
    return cover_of(k, atomicLoad(&slots[k * SLOTS + s]));
}

// The particle of the slot key `key` of cell k, and its solid fraction as `cover` computed it (the
// same function of the same values: the cell centre in the particle's box, one period away where
// the box wraps).
fn cover_of(k: u32, key: u32) -> Cover {
    let p = particles[slot_particle(key)];
    let t = box_offset(k, p);
    let x = vec3<f32>(box_origin(p) + t) + 0.5;
    return Cover(p, t, x, solid_fraction(x, p.pos_r.xyz, p.pos_r.w));
}

// With SUPERPOSITION, what the solid term keeps of the fluid's own collision, post - S - f (S: the
// body force's part of post, `forcing`); zero otherwise.
fn own_collision(f: array<f32, 19>, m: Moments, post: array<f32, 19>) -> array<f32, 19> {
    var own: array<f32, 19>;
    if SUPERPOSITION {
        var source: array<f32, 19>;
        if FORCE {
            source = forcing(m);
        }
        //#for i
        own[{i}] = post[{i}] - source[{i}] - f[{i}];
        //#end
    }
    return own;
}

// Particle p's solid term in a covered cell (its offset t in the particle's box, its centre x,
// the particle's weight b), added to `out`: b Omega_i with Omega_i = f_ibar - f_i + f_eq_i(rho,
// u_s) - f_eq_ibar(rho, u) (seed eq. 8), or with SUPERPOSITION Omega_i = f_eq_i(rho, u_s) -
// f_eq_i(rho, u) + own_i, where u_s is the solid's velocity at the cell centre (eq. 9, at x
// rather than half a link on). The momentum it takes from the fluid, -b sum_i Omega_i c_i (the
// cell's term of eq. 10), goes to the particle's pair of this cell for `reduce`.
fn solid_collision(
    p: Particle,
    t: vec3<i32>,
    x: vec3<f32>,
    b: f32,
    f: array<f32, 19>,
    m: Moments,
    own: array<f32, 19>,
    fluid: array<f32, 19>,
) -> array<f32, 19> {
    var out = fluid;
    let solid = p.vel.xyz + cross(p.omega.xyz, x - p.pos_r.xyz);
    // f_eq_i(rho, u_s) - f_eq_ibar(rho, u) = w_i rho (3 c.sum + 4.5 (c.sum)(c.diff) - 1.5 sum.diff)
    // with sum = u_s + u, diff = u_s - u (eq. 3); f_eq_i(rho, u_s) - f_eq_i(rho, u) the same with
    // 3 c.diff in place of 3 c.sum.
    let sum = solid + m.u;
    let diff = solid - m.u;
    let scalar = -1.5 * dot(sum, diff);
    var momentum = vec3<f32>(0.0);
    //#for i
    {
        let c = vec3<f32>({i.cx}.0, {i.cy}.0, {i.cz}.0);
        let cs = dot(c, sum);
        let cd = dot(c, diff);
        var omega: f32;
        if SUPERPOSITION {
            omega = b * ({i.w} * m.rho * (3.0 * cd + 4.5 * cs * cd + scalar) + own[{i}]);
        } else {
            omega = b * (f[{i.o}] - f[{i}] + {i.w} * m.rho * (3.0 * cs + 4.5 * cs * cd + scalar));
        }
        out[{i}] += omega;
        momentum += omega * c;
    }
    //#end
    let b_ = vec3<u32>(t);
    let m_ = p.edge;
    pairs[p.first + b_.x + m_ * (b_.y + m_ * b_.z)] = vec4<f32>(-momentum, 1.0);
    return out;
}

