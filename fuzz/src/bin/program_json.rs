//! AFL harness for `mp_fuzz::program_json`.

fn main() {
    afl::fuzz!(|data: &[u8]| {
        mp_fuzz::program_json(data);
    });
}
