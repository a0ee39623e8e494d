import { defineConfig } from "vite";
import preact from "@preact/preset-vite";

// `npm run dev` proxies the API to a service started with `make run`.
export default defineConfig({
  plugins: [preact()],
  server: {
    proxy: { "/api": { target: "http://127.0.0.1:8000", ws: true } },
  },
  build: {
    outDir: "dist",
    emptyOutDir: true,
    sourcemap: true,
    // the HMI, and the API documentation with its assets served by us (no CDN)
    rollupOptions: { input: { main: "index.html", docs: "docs.html" } },
    chunkSizeWarningLimit: 1600, // the docs page is Swagger UI in one chunk (1.5 MB)
  },
});
