//! AFL harness for `mp_fuzz::concrete_dsl`.

fn main() {
    afl::fuzz!(|data: &[u8]| {
        mp_fuzz::concrete_dsl(data);
    });
}
