// The API documentation page (/docs): Swagger UI from our own bundle, never from a CDN, so
// the page works offline and satisfies the service's Content-Security-Policy.
import SwaggerUI from "swagger-ui-dist/swagger-ui-es-bundle.js";
import "swagger-ui-dist/swagger-ui.css";

SwaggerUI({ url: "/openapi.json", dom_id: "#swagger-ui", deepLinking: true });
