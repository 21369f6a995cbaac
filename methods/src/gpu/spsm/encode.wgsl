// DerivativeCode::encode by its thresholds (the smallest slope of each code, 1 to 254), read
// from `tables[512..768)` (the code's tables, `texel::code_tables`), which the including
// kernel binds.
fn encode(s: f64) -> u32 {
    if s != s {
        return 127u;
    }
    var lo = 0u;
    var hi = 254u;
    while lo < hi {
        let mid = (lo + hi + 1u) / 2u;
        if s >= tables[512u + mid] {
            lo = mid;
        } else {
            hi = mid - 1u;
        }
    }
    return lo;
}
