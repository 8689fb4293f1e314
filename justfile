# Everyday recipes (https://github.com/casey/just). All builds use the one release profile.
export CARGO_TARGET_DIR := env_var_or_default("CARGO_TARGET_DIR", env_var("HOME") + "/.cache/gyrolab/target")

# Record a few shipped scenes into recordings/ and print what they show
demo:
    cargo run --release -p gyrolab -- demo

# Run a scene (name or path): just run harbour-50n
run scene *args:
    cargo run --release -p gyrolab -- run {{scene}} {{args}}

# The test suite (what CI runs)
test:
    cargo test --release --workspace

# Criterion benchmarks
bench:
    cargo bench --workspace

# Show a recording in Rerun
view recording *args:
    cargo run --release -p gyrolab -- view {{recording}} {{args}}

lint:
    cargo fmt --all --check
    cargo clippy --workspace --release --all-targets -- -D warnings
