import { defineConfig } from "vite";

// The server (crates/surfaces/situate_gui) embeds dist/ at compile time and serves it at /.
export default defineConfig({
  base: "/",
  build: { outDir: "dist", emptyOutDir: true, sourcemap: false, target: "es2022" },
  server: { proxy: { "/ws": { target: "ws://127.0.0.1:8080", ws: true } } },
});
