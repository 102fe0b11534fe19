//! AFL harness for `mp_fuzz::abstract_dsl`.

fn main() {
    afl::fuzz!(|data: &[u8]| {
        mp_fuzz::abstract_dsl(data);
    });
}
