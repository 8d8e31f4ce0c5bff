# Multi-stage build: compile in the Rust image, run in a small Debian image.
FROM rust:1-bookworm AS build
WORKDIR /src
COPY Cargo.toml Cargo.lock build.rs rustfmt.toml ./
COPY src src
COPY migrations migrations
COPY api api
COPY benches benches
COPY examples examples
COPY web web
# --locked: the image builds exactly the dependency versions of Cargo.lock;
# the release profile keeps line tables for backtraces, which the image does not need
RUN cargo build --release --locked --bin shapeflow && strip target/release/shapeflow

FROM debian:bookworm-slim
RUN useradd --system --home /data shapeflow && mkdir -p /data && chown shapeflow /data
COPY --from=build /src/target/release/shapeflow /usr/local/bin/shapeflow
COPY examples /usr/share/shapeflow/examples
USER shapeflow
VOLUME /data
EXPOSE 8080
# readiness: the database takes writes, the blobs can be written, the disk has room
HEALTHCHECK --interval=15s --timeout=6s --start-period=10s --retries=3 \
    CMD ["shapeflow", "health", "--url", "127.0.0.1:8080/readyz"]
ENTRYPOINT ["shapeflow"]
CMD ["serve", "--bind", "0.0.0.0:8080", "--data-dir", "/data"]
