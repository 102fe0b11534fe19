//! AFL harness for `mp_fuzz::bvh`.

fn main() {
    afl::fuzz!(|data: &[u8]| {
        mp_fuzz::bvh(data);
    });
}
